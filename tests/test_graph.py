"""The style graph: fused view graphs, spectral cut, automatic number of clusters."""
import numpy as np

from style_coanalysis import graph


def _blobs(sizes, dim=5, spread=0.15, seed=0):
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(len(sizes), dim)) * 2
    x = np.concatenate([c + spread * rng.normal(size=(s, dim)) for c, s in zip(centres, sizes)])
    return x, np.repeat(np.arange(len(sizes)), sizes)


def test_partition_recovers_separated_groups_whatever_their_order():
    from sklearn.metrics import adjusted_rand_score
    x, truth = _blobs([15, 20, 25])
    lab = graph.partition(graph.affinity(x), 3)
    assert adjusted_rand_score(truth, lab) == 1.0
    perm = np.random.default_rng(1).permutation(len(x))
    again = graph.partition(graph.affinity(x[perm]), 3)
    back = np.empty_like(again)
    back[perm] = again
    assert adjusted_rand_score(lab, back) == 1.0


def test_choose_n_clusters_finds_the_spectral_gap():
    for k in (2, 3, 5):
        x, _ = _blobs([12] * k, seed=k)
        gaps = graph.spectral_gaps(graph.affinity(x), 10)
        assert set(gaps) == set(range(2, 11)) and graph.choose_n_clusters(gaps) == k
        assert all(gaps[k] > 2 * g for j, g in gaps.items() if j != k)   # clearly ahead
    assert graph.choose_n_clusters({2: 0.1, 3: 0.3, 4: 0.3}) == 3        # a tie: the fewer
    assert graph.spectral_gaps(graph.affinity(_blobs([1, 1], seed=0)[0]), 10) == {2: 0.0}


def test_fusion_keeps_what_the_views_agree_on():
    """Two views share the true grouping; each also has a grouping of its own that crosses it.
    Each view alone is cut along either; the fused graph is cut along the shared one."""
    from sklearn.metrics import adjusted_rand_score
    rng = np.random.default_rng(0)
    n = 60
    shared = np.repeat([0, 1], 30)
    own1, own2 = np.tile([0, 1], 30), rng.permutation(shared)
    v1 = np.c_[np.eye(2)[shared], 0.9 * np.eye(2)[own1]] + 0.1 * rng.normal(size=(n, 4))
    v2 = np.c_[np.eye(2)[shared], 0.9 * np.eye(2)[own2]] + 0.1 * rng.normal(size=(n, 4))
    fused = graph.fuse([graph.affinity(v1), graph.affinity(v2)])
    assert adjusted_rand_score(shared, graph.partition(fused, 2)) == 1.0
    weights_one = graph.fuse([graph.affinity(v1), graph.affinity(v2)], [1.0, 0.0])
    np.testing.assert_allclose(weights_one.toarray(), graph.affinity(v1).toarray())


def test_each_view_graph_is_sparse_symmetric_and_keeps_ties():
    """Every shape keeps its nearest shapes (at least N_EDGES edges), the graph is symmetric and
    grows with N, not N^2; and shapes tied with the last neighbour kept are kept too, so the
    graph of a collection with duplicates does not depend on the order."""
    x, _ = _blobs([300, 300, 300], seed=4)
    a = graph.affinity(x)
    n = len(x)
    deg = np.diff(a.indptr)
    assert deg.min() >= graph.N_EDGES and a.nnz <= 2 * graph.N_EDGES * n
    assert abs(a - a.T).max() == 0 and a.diagonal().max() == 0
    dup = np.repeat(x[:40], 3, axis=0)                   # every point three times
    perm = np.random.default_rng(0).permutation(len(dup))
    g, gp = graph.affinity(dup).toarray(), graph.affinity(dup[perm]).toarray()
    np.testing.assert_allclose(gp, g[np.ix_(perm, perm)])


def test_view_graph_is_the_nearest_shapes_of_the_whole_distance_matrix():
    """The k-nearest search keeps each shape's N_EDGES nearest with the local-scaling weights of
    the whole distance matrix; on a grid, where many distances tie exactly but round apart,
    every tie is kept whatever the order of the shapes."""
    from scipy.spatial.distance import cdist
    x, _ = _blobs([200, 150], seed=6)
    d2 = cdist(x, x, "sqeuclidean")
    np.fill_diagonal(d2, np.inf)
    order = np.sort(d2, axis=1)
    sigma = np.sqrt(order[:, graph.K_NEIGHBOURS - 1])
    keep = d2 <= order[:, graph.N_EDGES - 1:graph.N_EDGES]
    ref = np.where(keep, np.exp(-d2 / np.outer(sigma, sigma)), 0.0)
    np.testing.assert_allclose(graph.affinity(x).toarray(), np.maximum(ref, ref.T), atol=1e-12)
    cells = np.random.default_rng(3).integers(0, 11, size=(400, 3))
    grid = cells * 0.73                                   # exact distances: the integer ones
    d2 = ((cells[:, None, :] - cells[None, :, :]) ** 2).sum(axis=2).astype(float)
    np.fill_diagonal(d2, np.inf)
    keep = d2 <= np.sort(d2, axis=1)[:, graph.N_EDGES - 1:graph.N_EDGES]
    a = graph.affinity(grid).toarray()
    np.testing.assert_array_equal(a > 0, keep | keep.T)
    for seed in range(3):
        perm = np.random.default_rng(seed).permutation(len(grid))
        np.testing.assert_array_equal(graph.affinity(grid[perm]).toarray(), a[np.ix_(perm, perm)])


def test_a_views_graph_is_the_mean_of_its_nearest_graphs_at_every_scale():
    """`ladder_affinities` takes every scale below N / 2, and the automatic k's graph, from one
    k-nearest search: the graphs each scale's own search gives (duplicated rows: ties at some
    scales), whatever the order of the shapes, whether or not the extra scale is a rung."""
    assert graph.edge_ladder(24) == [5, 10] and graph.edge_ladder(120) == [5, 10, 20, 40]
    assert graph.edge_ladder(8) == [5] and graph.edge_ladder(5000) == list(graph.EDGE_LADDER)
    x, _ = _blobs([60, 40, 30], seed=7)
    x = np.vstack([x, x[:12]])                            # duplicates: rows with ties
    for rows in (x, x[:50], x[:24]):       # 40 nearest a rung, then not, then all N - 1
        mean = graph.fuse([graph.affinity(rows, n_edges=e) for e in graph.edge_ladder(len(rows))])
        a, (choice,) = graph.ladder_affinities(rows, [graph.CHOICE_EDGES])
        assert (a != mean).nnz == 0
        assert (choice != graph.affinity(rows, n_edges=graph.CHOICE_EDGES)).nnz == 0
        assert (graph.ladder_affinities(rows)[0] != a).nnz == 0
    perm = np.random.default_rng(1).permutation(len(x))
    a, (choice,) = graph.ladder_affinities(x, [graph.CHOICE_EDGES])
    a_p, (choice_p,) = graph.ladder_affinities(x[perm], [graph.CHOICE_EDGES])
    np.testing.assert_array_equal(a_p.toarray(), a.toarray()[np.ix_(perm, perm)])
    np.testing.assert_array_equal(choice_p.toarray(), choice.toarray()[np.ix_(perm, perm)])


def test_large_graphs_are_solved_like_small_ones():
    """The Lanczos solver used above DENSE_BELOW shapes finds the dense solver's eigenvalues."""
    from scipy.linalg import eigh
    x, _ = _blobs([150, 150, 100], seed=5)
    a = graph.affinity(x)
    w, u = graph.embedding(a, 4)
    d = 1 / np.sqrt(np.asarray(a.sum(axis=1)).ravel())
    dense = eigh(a.toarray() * d[:, None] * d[None, :], eigvals_only=True)[::-1][:4]
    assert len(x) >= graph.DENSE_BELOW
    np.testing.assert_allclose(w, dense, atol=1e-8)
