"""Self-tuning spectral clustering, triplet-constrained clustering, style distance."""
import numpy as np
import pytest
from sklearn.cluster import KMeans
from sklearn.metrics import adjusted_rand_score
from sklearn.metrics.cluster import contingency_matrix
from sklearn.preprocessing import normalize

from style_coanalysis.clustering import (SelfTuningSpectralClustering, TripletClustering,
                                         must_cannot_from_triplets, predict_triplets,
                                         rotation_cost, style_distance)


def purity(y, labels):
    c = contingency_matrix(y, labels)
    return c.max(axis=0).sum() / c.sum()


def blobs(k, seed, per=35):
    """k Gaussian blobs on a circle, spreads from 0.4 to 1.6 (local scaling must cope)."""
    rng = np.random.RandomState(seed)
    ang = 2 * np.pi * np.arange(k) / k + rng.uniform(0, 1)
    centres = 14.0 * np.c_[np.cos(ang), np.sin(ang)]
    spreads = np.linspace(0.4, 1.6, k)[rng.permutation(k)]
    X = np.vstack([c + s * rng.randn(per, 2) for c, s in zip(centres, spreads)])
    return X, np.repeat(np.arange(k), per)


@pytest.mark.parametrize("k", [3, 4, 5])
def test_self_tuning_finds_number_of_blobs(k):
    X, y = blobs(k, seed=k)
    m = SelfTuningSpectralClustering(max_clusters=8, random_state=0)
    labels = m.fit_predict(X)
    assert m.n_clusters_ == k, m.rotation_costs_
    assert adjusted_rand_score(y, labels) > 0.95
    assert set(m.rotation_costs_) == set(range(2, 9))
    A = m.affinity_matrix_
    assert np.allclose(A, A.T) and np.all(np.diag(A) == 0) and A.max() <= 1


def test_self_tuning_fixed_number_of_clusters():
    X, y = blobs(4, seed=1)
    m = SelfTuningSpectralClustering(n_clusters=4, random_state=0).fit(X)
    assert m.n_clusters_ == 4 and m.rotation_costs_ == {}
    assert adjusted_rand_score(y, m.labels_) > 0.95


def test_rotation_cost_zero_for_indicator_like_vectors_and_positive_otherwise():
    rng = np.random.RandomState(0)
    Y = np.eye(3)[rng.randint(3, size=60)]
    Y = Y / np.linalg.norm(Y, axis=0)
    R, _ = np.linalg.qr(rng.randn(3, 3))
    cost, Z = rotation_cost(Y @ R)               # a rotated indicator basis: rotatable back
    assert cost < 1e-6
    cost_noise, _ = rotation_cost(np.linalg.qr(rng.randn(60, 3))[0])
    assert cost_noise > 0.05


def test_must_cannot_from_triplets():
    must, cannot = must_cannot_from_triplets(np.array([[0, 1, 2], [1, 0, 3], [2, 2, 4]]))
    assert must.tolist() == [[0, 1]]                 # duplicates merged, self-pair dropped
    assert cannot.tolist() == [[0, 2], [1, 3], [2, 4]]
    with pytest.raises(ValueError, match="shape"):
        must_cannot_from_triplets(np.array([[0, 1]]))


def competing_features(seed, n=120, d=20):
    rng = np.random.RandomState(seed)
    cat, sty = rng.randint(3, size=n), rng.randint(3, size=n)
    V = (1.4 * np.eye(3)[cat] @ rng.gamma(0.5, 1, (3, d))
         + np.eye(3)[sty] @ rng.gamma(0.5, 1, (3, d)) + 0.3 * rng.rand(n, d))
    return V, cat, sty


def style_triplets(sty, t, rng):
    out = []
    while len(out) < t:
        a, b, c = rng.randint(sty.size, size=3)
        if a != b and sty[a] == sty[b] != sty[c]:
            out.append((a, b, c))
    return np.array(out)


def test_triplets_raise_purity_towards_the_weaker_structure():
    unsup, tri = [], []
    for seed in range(3):
        V, cat, sty = competing_features(seed)
        T = style_triplets(sty, 3 * sty.size, np.random.RandomState(seed))
        unsup.append(purity(sty, KMeans(3, n_init=10, random_state=0).fit_predict(normalize(V))))
        m = TripletClustering(3, random_state=0).fit(V, T)
        tri.append(purity(sty, m.labels_))
        np.testing.assert_allclose(m.membership_.sum(axis=1), 1.0)
        assert np.all(np.diff(m.objective_history_) <= 1e-9 * m.objective_history_[0])
    assert np.mean(unsup) < 0.5
    assert np.mean(tri) > np.mean(unsup) + 0.2, (unsup, tri)


def test_triplet_clustering_without_triplets_is_plain_clustering():
    X, y = blobs(3, seed=0)
    V = np.abs(X - X.min(0)) + 0.1
    V = np.c_[V, np.eye(3)[y] * 5]                   # clear clusters in cosine terms
    labels = TripletClustering(3, random_state=0).fit_predict(V, np.zeros((0, 3), int))
    assert adjusted_rand_score(y, labels) > 0.9


def test_triplet_clustering_starts_from_the_graph_it_is_given():
    """The analysis passes its style graph: the spectral start reads that graph, not a kNN graph
    of the features; a graph of the wrong size is refused."""
    from scipy import sparse
    V, cat, sty = competing_features(0)
    rng = np.random.RandomState(0)
    noise = rng.uniform(0, 0.2, (sty.size, sty.size))
    graph = sparse.csr_matrix(np.where(sty[:, None] == sty[None, :], 0.8, 0.0) + noise)
    own = TripletClustering(3, random_state=0).fit_predict(V, None)
    given = TripletClustering(3, random_state=0).fit_predict(V, None, affinity=graph)
    assert purity(sty, given) > 0.95 > purity(sty, own) + 0.1, \
        (purity(sty, given), purity(sty, own))
    with pytest.raises(ValueError, match="affinity"):
        TripletClustering(3, random_state=0).fit(V, None, affinity=np.eye(5))


def test_style_distance_and_triplet_prediction():
    V = np.array([[1.0, 0.0], [2.0, 0.1], [0.0, 1.0], [0.1, 3.0]])
    D = style_distance(V)
    assert np.allclose(D, D.T) and np.allclose(np.diag(D), 0) and D.min() >= 0
    assert D[0, 1] < 0.01 and D[0, 2] > 0.9          # scale-free: cosine of normalised rows
    pred = predict_triplets(D, np.array([[0, 1, 2], [0, 2, 1], [2, 3, 0]]))
    assert pred.tolist() == [True, False, True]
    with pytest.raises(ValueError, match="indices"):
        predict_triplets(D, np.array([[0, 1, 9]]))


def test_sparse_triplets_propagate_and_give_exactly_c_clusters():
    """Few triplets: the must-link closure and the constrained graph carry them to the whole
    collection; every must-link component ends in one cluster; C clusters, none empty."""
    from style_coanalysis.clustering import closed_constraints
    pur, unsup = [], []
    for seed in range(3):
        V, cat, sty = competing_features(seed)
        T = style_triplets(sty, sty.size // 2, np.random.RandomState(seed))
        m = TripletClustering(3, random_state=0).fit(V, T)
        assert len(np.unique(m.labels_)) == 3
        comp = m.components_
        for g in np.unique(comp):
            assert len(np.unique(m.labels_[comp == g])) == 1
        assert m.n_implied_must_links_ >= m.n_must_links_
        pur.append(purity(sty, m.labels_))
        unsup.append(purity(sty, TripletClustering(3, random_state=0).fit_predict(V, None)))
    assert np.mean(pur) > 0.9 and np.mean(pur) > np.mean(unsup) + 0.3, (pur, unsup)
    comp, same, diff = closed_constraints(np.array([[0, 1], [1, 2]]), np.array([[0, 3], [1, 2]]), 5)
    assert same[0, 2] and diff[2, 3] and not diff[1, 2]     # closure; contradicting pair dropped


def test_triplet_clustering_does_not_depend_on_the_order_of_the_shapes():
    """The same shapes and triplets in another order give the same partition: the spectral
    start's k-means runs on the rows in a canonical order. Shapes spread evenly, with no clear
    clusters, where k-means' starts decide the cut (in the input order, 4 of these 4 cuts moved
    with the order)."""
    n = 150
    trip = np.array([[0, 1, 2], [3, 4, 5]])
    p = np.random.RandomState(100).permutation(n)
    inv = np.argsort(p)
    for seed in range(4):
        V = np.random.RandomState(seed).uniform(0, 1, (n, 6)) + 0.1
        ref = TripletClustering(10, random_state=0, metric=False).fit_predict(V, trip)
        got = TripletClustering(10, random_state=0, metric=False).fit_predict(V[p], inv[trip])
        assert adjusted_rand_score(ref, got[inv]) == 1.0, seed
