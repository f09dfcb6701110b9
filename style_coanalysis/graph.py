"""The style graph: one similarity graph per view, fused, then cut into style clusters.

Why graphs rather than one feature matrix: the views (views.word_views, line character) disagree
where they see structure rather than style (the view compared with few look-alikes sees noise,
the one compared with the whole collection sees category), and agree on style. A weighted mean
of the views' graphs keeps an edge strong only where several views make it, so what they agree
on dominates the cut; the spectral cut then needs no assumption on cluster shape. Measured on the
17 benchmark collections with k given (bench/bench_fusion.py, 3 seeds, same encoding, each graph
of the 20 nearest), sum of the mean style purities: this mean 12.07, PSLF over the same views
10.53 (below on 14 of 17), concatenation 11.98, PCA of it 11.61 (README). The views weigh the
same: weights from each view's spectral gap at k, or AMGL's (Nie et al. 2016, a view's weight
falling with its roughness on the fused cut) gave 5.38 and 5.37 against 5.45 on the first 8
collections.

Each view's graph links every shape to its nearest shapes (and theirs to it), with the
local-scaling affinity of self-tuning spectral clustering (Zelnik-Manor and Perona 2004):
A_ij = exp(-d_ij^2 / (s_i s_j)), s_i the distance to the i-th shape's 7th neighbour (their
value), so dense and sparse parts of a view are treated alike. How many nearest: all of 5, 10,
20 and 40 below N / 2, their graphs averaged (`ladder_affinities`), so a pair's weight also
counts the scales that link it and no one neighbour count is chosen for the collection.
Why a sparse graph: beyond its nearest shapes a shape's affinities only order shapes that are
not alike, which the cut should not read, and a dense graph costs N^2 memory and an N^3
eigensolver (5,000 shapes: 200 MB per view). Measured on the generalisation benchmark (17
collections, 3 seeds; sum of the mean style purities per mode). One dictionary, k given /
automatic / 2 labels per style / 20% labels: every shape linked to all 11.76 / 10.72 / 12.05 /
12.81, to its 40 nearest 11.79 / 10.86 / 12.17 / 12.66, to its 20 nearest 12.10 / 11.00 /
12.39 / 12.99 (generalisation_f/k/j.json). Five dictionaries, k given: 40 nearest 11.89, 20
12.07, 15 11.97, 10 12.41, 5 12.36, the ladder 12.35; 10 nearest and the ladder against 20:
automatic k 11.13 and 11.11 against 11.05, 2 labels 12.67 and 12.65 against 12.49, 20% labels
13.43 and 13.39 against 13.19. Ten nearest alone moved with the drawings: collection2 read
back from .blend ARI 0.67 with k given (0.95 with 20), from OBJ with automatic k 0.69 (0.87),
sample-120 from OBJ 0.82 (0.98); the ladder keeps them (docs/generalisation.md). Scales of
80 and 160 as well (for N above 160 and 320) cost 3x per shape at 5,000 shapes and scored lower
on hu2017-all (537 shapes, k given 0.427 against 0.435, with the eight-rung look-alike ladder
of then). The automatic k reads 40-nearest graphs
(`pipeline._cluster_count_gaps`; the ladder's graph instead: right on 15 of 51 runs, against
27). Only each shape's nearest are held, so memory grows with N, not N^2, and a view's graph
costs the same per shape at any N but for the all-pairs search.

Order of the input: every step is equivariant to a permutation of the shapes (a neighbour tied
with the last one kept is kept too) except k-means' initialisation, so k-means runs on the rows
in a canonical order (sorted by their rounded values) and its answer is mapped back: the same
shapes give the same partition whatever order they were read in.
"""
from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.linalg import eigh
from scipy.sparse.linalg import eigsh
from sklearn.cluster import KMeans
from sklearn.metrics import pairwise_distances
from sklearn.neighbors import NearestNeighbors
from sklearn.preprocessing import normalize
from threadpoolctl import threadpool_limits

K_NEIGHBOURS = 7          # the local scale: distance to the 7th neighbour (Zelnik-Manor, Perona)
N_EDGES = 20              # a nearest-shape graph's edges (`affinity`)
CHOICE_EDGES = 40         # the edges of the graphs the automatic k reads
EDGE_LADDER = (5, 10, 20, 40)            # the scales of a view's graph (`ladder_affinities`)
BLOCK = 256               # whole distance rows held at once (rows with ties)
TIE = 1e-9                # distances this close (relative to the squared norms) are ties
DENSE_BELOW = 300         # smaller graphs are solved densely (exact, and faster there)


def affinity(x: np.ndarray, k_neighbours: int = K_NEIGHBOURS,
             n_edges: int = N_EDGES) -> sparse.csr_matrix:
    """Local-scaling affinity of the rows of x between each row and its `n_edges` nearest rows
    (and every row tied with the last of them), symmetrised: (N, N) sparse, zero diagonal.

    The nearest rows come from scikit-learn's brute-force k-nearest search (chunked, compiled,
    both cores), which keeps only each row's m + 1 nearest rather than a block of all distances:
    a view of 5,000 shapes takes 53 ms instead of 400 ms. A row whose (m+1)-th
    nearest ties its m-th (a duplicated shape, points on a grid) takes all its ties, from its
    whole distance row. Ties are equal up to the rounding of |a|^2 + |b|^2 - 2 a.b (`TIE` of
    |a|^2 + max |b|^2), which depends on where a row sits in the computation's blocks, so
    that the graph does not depend on the order of the shapes."""
    return affinities(x, [n_edges], k_neighbours)[0]


def affinities(x: np.ndarray, edges, k_neighbours: int = K_NEIGHBOURS) -> list:
    """`affinity(x, k_neighbours, e)` for every e of `edges`, from one k-nearest search."""
    x = np.asarray(x, np.float64)
    n = len(x)
    k = min(k_neighbours, n - 1)
    ms = [min(max(int(e), k), n - 1) for e in edges]
    sq = np.einsum("ij,ij->i", x, x)
    tol = TIE * (sq + sq.max(initial=0.0))
    if min(ms) < n - 1:                            # (a graph of all N - 1 reads whole rows)
        d2, nbr = NearestNeighbors(n_neighbors=min(max(ms) + 1, n - 1), algorithm="brute",
                                   metric="sqeuclidean") \
            .fit(x).kneighbors()                   # ascending; a row is not its own neighbour
        knn_sigma = np.sqrt(np.maximum(d2[:, k - 1], 1e-24))
    else:
        d2, nbr, knn_sigma = np.zeros((n, 0)), np.zeros((n, 0), np.int64), np.empty(n)
    return [_nearest_graph(x, d2, nbr, knn_sigma, m, k, tol) for m in ms]


def _nearest_graph(x, d2, nbr, knn_sigma, m: int, k: int, tol) -> sparse.csr_matrix:
    """The graph of each row's m nearest (`affinity`), from the k-nearest search's
    ascending squared distances `d2` and indices `nbr` (at least m + 1 columns unless m = N - 1)."""
    n = len(x)
    sigma = knn_sigma.copy()
    if m < n - 1:
        tied = d2[:, m] <= d2[:, m - 1] + tol
    else:                                          # every other row is a neighbour
        tied = np.ones(n, bool)
    plain = np.flatnonzero(~tied)
    rows, cols, d2s = [np.repeat(plain, m)], [nbr[plain, :m].ravel()], [d2[plain, :m].ravel()]
    whole = np.flatnonzero(tied)
    for start in range(0, len(whole), BLOCK):     # rows whose ties reach past the m-th
        sub = whole[start:start + BLOCK]
        row = pairwise_distances(x[sub], x, metric="sqeuclidean")
        row[np.arange(len(sub)), sub] = np.inf    # not its own neighbour
        part = np.partition(row, [k - 1, m - 1], axis=1)
        sigma[sub] = np.sqrt(np.maximum(part[:, k - 1], 1e-24))
        r, c = np.nonzero(row <= part[:, m - 1:m] + tol[sub, None])
        rows.append(sub[r])
        cols.append(c)
        d2s.append(row[r, c])
    r, c, d2v = np.concatenate(rows), np.concatenate(cols), np.concatenate(d2s)
    a = sparse.csr_matrix((np.exp(-d2v / (sigma[r] * sigma[c])), (r, c)), shape=(n, n))
    return a.maximum(a.T).tocsr()


def edge_ladder(n: int) -> list:
    """The scales of `ladder_affinities` for N shapes: those of `EDGE_LADDER` below N / 2 (at
    least the first)."""
    return [e for e in EDGE_LADDER if e < n / 2] or [EDGE_LADDER[0]]


def ladder_affinities(x: np.ndarray, extra_edges=(),
                      k_neighbours: int = K_NEIGHBOURS) -> tuple:
    """The mean of the nearest-shape graphs (`affinity`) at every scale of `edge_ladder(N)`, and
    the graphs at `extra_edges` nearest, all from one k-nearest search (a scale both ask for is
    built once). In the mean a pair's weight grows with the number of scales that link it, so
    each shape's nearest count most, and no one neighbour count is chosen for the collection
    at hand."""
    ladder = edge_ladder(len(x))
    edges = list(dict.fromkeys([*ladder, *extra_edges]))
    made = dict(zip(edges, affinities(x, edges, k_neighbours)))
    return fuse([made[e] for e in ladder]), [made[e] for e in extra_edges]


def fuse(graphs: list, weights=None) -> sparse.csr_matrix:
    """Weighted mean of the views' graphs (uniform weights by default)."""
    w = np.full(len(graphs), 1.0 / len(graphs)) if weights is None else \
        np.asarray(weights, np.float64) / max(float(np.sum(weights)), 1e-12)
    out = sparse.csr_matrix(graphs[0].shape)
    for wi, g in zip(w, graphs):
        out = out + wi * sparse.csr_matrix(g)
    return out.tocsr()


def embedding(a, n_vectors: int) -> tuple[np.ndarray, np.ndarray]:
    """Top eigenvalues (descending) and eigenvectors of the normalised affinity D^-1/2 A D^-1/2
    (dense solver for small graphs, Lanczos (ARPACK) from a fixed start for large ones)."""
    a = sparse.csr_matrix(a)
    n = a.shape[0]
    dinv = sparse.diags(1.0 / np.sqrt(np.maximum(np.asarray(a.sum(axis=1)).ravel(), 1e-12)))
    sym = (dinv @ a @ dinv).tocsr()
    m = int(min(n_vectors, n))
    if n < DENSE_BELOW or m >= n - 1:
        w, u = eigh(sym.toarray(), subset_by_index=[n - m, n - 1])
    else:
        w, u = eigsh(sym, k=m, which="LA", v0=np.ones(n))
    order = np.argsort(-w, kind="stable")
    return w[order], fixed_signs(u[:, order])


def fixed_signs(u: np.ndarray) -> np.ndarray:
    """Eigenvectors (columns) with their arbitrary signs fixed by their largest entry, so the
    coordinates (and the canonical order k-means runs in) depend on the shapes only."""
    big = u[np.argmax(np.abs(u), axis=0), np.arange(u.shape[1])]
    return u * np.where(big < 0, -1.0, 1.0)


def canonical_order(x: np.ndarray, decimals: int = 6) -> np.ndarray:
    """A permutation that sorts the rows by their rounded values: the same rows give the same
    order whatever order they came in."""
    r = np.round(np.asarray(x, np.float64), decimals)
    return np.lexsort(r.T[::-1])


def kmeans(x: np.ndarray, n_clusters: int, random_state: int = 0) -> np.ndarray:
    """k-means (20 starts) run on the rows in canonical order; labels in the input order.
    On one thread: the rows are a few coordinates each, and on more threads scikit-learn's
    OpenMP pool and the BLAS pool wait on each other (a seeded k-means on 3,000 x 4
    coordinates: 2 ms on one thread, 65 ms on two; the same labels)."""
    order = canonical_order(x)
    with threadpool_limits(limits=1):
        lab = KMeans(n_clusters, n_init=20, random_state=random_state).fit_predict(x[order])
    out = np.empty(len(x), np.int64)
    out[order] = lab
    return out


def partition(a, n_clusters: int, random_state: int = 0) -> np.ndarray:
    """Spectral cut of the graph into n_clusters (Ng-Jordan-Weiss: k-means on unit rows of the
    top eigenvectors)."""
    if n_clusters <= 1:
        return np.zeros(a.shape[0], np.int64)
    _, u = embedding(a, n_clusters)
    return kmeans(normalize(u), n_clusters, random_state)


def spectral_gaps(a, max_clusters: int) -> dict[int, float]:
    """{k: the normalised affinity's spectral gap after eigenvalue k} for k = 2..max (at least
    {2: 0.0}): how strongly the graph holds k groups. Eigenvalue k is near 1 for each of k
    well-separated groups; the first big drop after it marks how many there are."""
    n = a.shape[0]
    top = int(max(2, min(max_clusters, n - 1)))
    w, _ = embedding(a, top + 1)
    gaps = w[1:top] - w[2:top + 1]          # gap after eigenvalue k, for k = 2..top
    return {k + 2: float(g) for k, g in enumerate(gaps)} if len(gaps) else {2: 0.0}


def choose_n_clusters(gaps: dict[int, float]) -> int:
    """The number of clusters at the largest of `spectral_gaps` (the smallest such k on a tie)."""
    return max(gaps, key=lambda k: (gaps[k], -k))
