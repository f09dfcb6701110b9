"""The style graph: one similarity graph per view, fused, then cut into style clusters.

Why graphs rather than one feature matrix: the views (views.fusion_views) disagree where they
see structure rather than style (the view compared with few look-alikes sees noise, the one
compared with the whole collection sees category), and agree on style. A weighted mean of the
views' graphs keeps an edge strong only where several views make it, so what they agree on
dominates the cut; the spectral cut then needs no assumption on cluster shape. Measured against
PSLF, concatenation and single views on every benchmark collection (README table).

Each view's graph is the local-scaling affinity of self-tuning spectral clustering (Zelnik-Manor
and Perona 2004): A_ij = exp(-d_ij^2 / (s_i s_j)), s_i the distance to the i-th shape's 7th
neighbour (their value), so dense and sparse parts of a view are treated alike.

Order of the input: every step is equivariant to a permutation of the shapes except k-means'
initialisation, so k-means runs on the rows in a canonical order (sorted by their rounded
values) and its answer is mapped back: the same shapes give the same partition whatever order
they were read in.
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import eigh
from sklearn.cluster import KMeans
from sklearn.metrics import pairwise_distances
from sklearn.preprocessing import normalize

K_NEIGHBOURS = 7


def affinity(x: np.ndarray, k_neighbours: int = K_NEIGHBOURS) -> np.ndarray:
    """Local-scaling affinity of the rows of x: (N, N), zero diagonal."""
    d2 = pairwise_distances(np.asarray(x, np.float64), metric="sqeuclidean")
    n = len(d2)
    k = min(k_neighbours, n - 1)
    sigma = np.sqrt(np.maximum(np.sort(d2, axis=1)[:, k], 1e-24))
    a = np.exp(-d2 / np.outer(sigma, sigma))
    np.fill_diagonal(a, 0.0)
    return a


def fuse(graphs: list[np.ndarray], weights=None) -> np.ndarray:
    """Weighted mean of the views' graphs (uniform weights by default)."""
    w = np.full(len(graphs), 1.0 / len(graphs)) if weights is None else \
        np.asarray(weights, np.float64) / max(float(np.sum(weights)), 1e-12)
    return np.tensordot(w, np.stack(graphs), axes=1)


def embedding(a: np.ndarray, n_vectors: int) -> tuple[np.ndarray, np.ndarray]:
    """Top eigenvalues (descending) and eigenvectors of the normalised affinity D^-1/2 A D^-1/2."""
    d = a.sum(axis=1)
    dinv = 1.0 / np.sqrt(np.maximum(d, 1e-12))
    sym = a * dinv[:, None] * dinv[None, :]
    n = len(a)
    m = int(min(n_vectors, n))
    w, u = eigh(sym, subset_by_index=[n - m, n - 1])
    w, u = w[::-1], u[:, ::-1]
    # an eigenvector's sign is arbitrary: fix it by its largest entry, so the coordinates (and
    # the canonical order k-means runs in) depend on the shapes only
    big = u[np.argmax(np.abs(u), axis=0), np.arange(u.shape[1])]
    return w, u * np.where(big < 0, -1.0, 1.0)


def canonical_order(x: np.ndarray, decimals: int = 6) -> np.ndarray:
    """A permutation that sorts the rows by their rounded values: the same rows give the same
    order whatever order they came in."""
    r = np.round(np.asarray(x, np.float64), decimals)
    return np.lexsort(r.T[::-1])


def kmeans(x: np.ndarray, n_clusters: int, random_state: int = 0) -> np.ndarray:
    """k-means (20 starts) run on the rows in canonical order; labels in the input order."""
    order = canonical_order(x)
    lab = KMeans(n_clusters, n_init=20, random_state=random_state).fit_predict(x[order])
    out = np.empty(len(x), np.int64)
    out[order] = lab
    return out


def partition(a: np.ndarray, n_clusters: int, random_state: int = 0) -> np.ndarray:
    """Spectral cut of the graph into n_clusters (Ng-Jordan-Weiss: k-means on unit rows of the
    top eigenvectors)."""
    if n_clusters <= 1:
        return np.zeros(len(a), np.int64)
    _, u = embedding(a, n_clusters)
    return kmeans(normalize(u), n_clusters, random_state)


def choose_n_clusters(a: np.ndarray, max_clusters: int) -> int:
    """The number of clusters at the largest gap of the normalised affinity's spectrum (2..max).

    Eigenvalue k of the normalised affinity is near 1 for each of k well-separated groups; the
    first big drop after it marks how many there are."""
    n = len(a)
    top = int(max(2, min(max_clusters, n - 1)))
    w, _ = embedding(a, top + 1)
    gaps = w[1:top] - w[2:top + 1]          # gap after eigenvalue k, for k = 2..top
    return int(np.argmax(gaps) + 2) if len(gaps) else 2
