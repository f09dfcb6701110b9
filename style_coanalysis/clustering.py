"""Style clustering on fused features (paper section 4.4).

* :class:`SelfTuningSpectralClustering`: unsupervised, picks the number of clusters itself
  (Zelnik-Manor & Perona 2004, local scaling + eigenvector rotation cost).
* :class:`TripletClustering`: eq. 3, "A is closer in style to B than to C" triplets turned into
  must-link / cannot-link edits of the similarity matrix, then a symmetric tri-factorisation.
* :func:`style_distance` / :func:`predict_triplets`: the style distance between shapes and the
  triplet prediction used in the evaluation (paper section 5).
"""
from __future__ import annotations

from itertools import combinations

import numpy as np
from scipy.linalg import eigh
from scipy.optimize import minimize
from scipy.sparse.linalg import eigsh
from sklearn.base import BaseEstimator, ClusterMixin
from sklearn.cluster import KMeans
from sklearn.metrics import pairwise_distances
from sklearn.neighbors import NearestNeighbors
from sklearn.preprocessing import normalize
from sklearn.utils import check_array, check_random_state


def _check_features(X, name="X"):
    X = check_array(X, dtype=np.float64, ensure_min_samples=2, input_name=name)
    return X


# ---------------------------------------------------------------------------------------------
# eigenvector rotation (Zelnik-Manor & Perona 2004)

def _givens_pairs(C):
    return list(combinations(range(C), 2))


def _rotation(theta, pairs, C):
    """R = G_1 G_2 ... G_K for Givens rotations G_k(theta_k) in planes pairs[k]."""
    R = np.eye(C)
    for t, (i, j) in zip(theta, pairs):
        c, s = np.cos(t), np.sin(t)
        Ri, Rj = R[:, i].copy(), R[:, j].copy()
        R[:, i] = c * Ri + s * Rj
        R[:, j] = -s * Ri + c * Rj
    return R


def _rotation_cost_grad(theta, X, pairs):
    """J = sum_ij Z_ij^2 / max_j Z_ij^2 for Z = X R(theta), and dJ/dtheta."""
    n, C = X.shape
    K = len(pairs)
    # prefix products L_k = G_1..G_{k-1} and suffix products S_k = G_{k+1}..G_K
    Gs = []
    for t, (i, j) in zip(theta, pairs):
        G = np.eye(C)
        c, s = np.cos(t), np.sin(t)
        G[i, i] = c; G[j, j] = c; G[j, i] = s; G[i, j] = -s
        Gs.append(G)
    prefix = [np.eye(C)]
    for G in Gs:
        prefix.append(prefix[-1] @ G)
    suffix = [np.eye(C)]
    for G in reversed(Gs):
        suffix.append(G @ suffix[-1])
    suffix = suffix[::-1]                  # suffix[k] = G_k..G_K (0-based, suffix[K] = I)
    R = prefix[K]
    Z = X @ R
    Z2 = Z ** 2
    m_idx = np.argmax(Z2, axis=1)
    M2 = Z2[np.arange(n), m_idx]
    # a row that is (numerically) zero is not represented by these eigenvectors at all (a
    # disconnected component beyond the first C): count it as the worst case, C, not as 0
    dead = M2 <= 1e-24 * max(M2.max(), 1e-300)
    M2 = np.where(dead, 1.0, M2)
    Z2 = np.where(dead[:, None], 0.0, Z2)
    Z = np.where(dead[:, None], 0.0, Z)
    J = float(np.sum(Z2 / M2[:, None])) + C * float(dead.sum())
    dR = np.empty((K, C, C))
    for k, (t, (i, j)) in enumerate(zip(theta, pairs)):
        dG = np.zeros((C, C))
        c, s = np.cos(t), np.sin(t)
        dG[i, i] = -s; dG[j, j] = -s; dG[j, i] = c; dG[i, j] = -c
        dR[k] = prefix[k] @ dG @ suffix[k + 1]
    A = np.einsum("nc,kcd->knd", X, dR)            # dZ/dtheta_k for every k
    rows = np.arange(n)
    Am = A[:, rows, m_idx]                         # (K, n)
    Zm = Z[rows, m_idx]
    grad = 2.0 * np.einsum("nd,knd->k", Z / M2[:, None], A) \
        - 2.0 * Am @ (Z2.sum(axis=1) / (M2 * Zm + np.copysign(1e-300, Zm)))
    return J, grad


def rotation_cost(X, n_restarts=0, random_state=None):
    """Best alignment cost of the rows of X (n x C) to the axes, and the rotated X.

    Minimises J with L-BFGS (its line search; run to real convergence: gtol 1e-8, ftol 1e-12)
    from theta = 0, i.e. from the incremental warm start, plus ``n_restarts`` random angles (off by
    default: in our tests they never beat the warm start and cost 10-100x the time); returns the normalised cost (J/n - 1)/C in [0, 1) (0 = every row on one axis; this is
    1 - quality of the original code) and Z = X R.
    """
    n, C = X.shape
    pairs = _givens_pairs(C)
    if not pairs:
        return 0.0, X.copy()
    rng = check_random_state(random_state)
    starts = [np.zeros(len(pairs))] + [rng.uniform(-np.pi, np.pi, len(pairs))
                                      for _ in range(n_restarts)]
    best = None
    for t0 in starts:
        res = minimize(_rotation_cost_grad, t0, args=(X, pairs), jac=True, method="L-BFGS-B",
                       options={"maxiter": 1000, "gtol": 1e-8, "ftol": 1e-12})
        if best is None or res.fun < best.fun:
            best = res
    Z = X @ _rotation(best.x, pairs, C)
    return (best.fun / n - 1.0) / C, Z


class SelfTuningSpectralClustering(ClusterMixin, BaseEstimator):
    """Spectral clustering with local scaling that chooses the number of clusters itself.

    Affinity A_ij = exp(-d_ij^2 / (sigma_i sigma_j)), sigma_i = distance to the k-th neighbour;
    L = D^-1/2 A D^-1/2. For C = min_clusters..max_clusters the top C eigenvectors are rotated
    (incrementally: the previous rotated set plus the next eigenvector, as in the authors' code)
    to align with the axes. The chosen C is the largest whose cost is within ``cost_tol`` of the
    best (the authors' rule: 0.001 in quality). Final labels: k-means on the row-normalised top-C
    eigenvectors (Ng-Jordan-Weiss), seeded by the rotation's argmax assignment.
    """

    def __init__(self, n_clusters=None, k_neighbors=7, max_clusters=10, min_clusters=2,
                 random_state=None, cost_tol=1e-3, n_restarts=0):
        self.n_clusters = n_clusters
        self.k_neighbors = k_neighbors
        self.max_clusters = max_clusters
        self.min_clusters = min_clusters
        self.random_state = random_state
        self.cost_tol = cost_tol
        self.n_restarts = n_restarts

    def _affinity(self, X):
        n = X.shape[0]
        k = min(int(self.k_neighbors), n - 1)
        if k < 1:
            raise ValueError("k_neighbors must be >= 1")
        dist, _ = NearestNeighbors(n_neighbors=k + 1).fit(X).kneighbors(X)
        sigma = np.maximum(dist[:, k], np.finfo(float).eps)
        D2 = pairwise_distances(X, metric="sqeuclidean")
        A = np.exp(-D2 / np.outer(sigma, sigma))
        np.fill_diagonal(A, 0.0)
        return A

    @staticmethod
    def _top_eigenvectors(A, C, rng):
        d = A.sum(axis=1)
        dinv = 1.0 / np.sqrt(np.maximum(d, np.finfo(float).tiny))
        L = A * dinv[:, None] * dinv[None, :]
        n = L.shape[0]
        if n <= 3000:
            w, U = eigh(L, subset_by_index=[n - C, n - 1])
        else:
            w, U = eigsh(L, k=C, which="LA", v0=rng.uniform(size=n))
        order = np.argsort(w)[::-1]
        return U[:, order]

    def fit(self, X, y=None):
        X = _check_features(X)
        n = X.shape[0]
        rng = check_random_state(self.random_state)
        A = self._affinity(X)
        self.affinity_matrix_ = A
        self.rotation_costs_ = {}
        if self.n_clusters is not None:
            C = int(self.n_clusters)
            if not 1 <= C <= n:
                raise ValueError(f"n_clusters must be in [1, {n}], got {self.n_clusters}")
            U = self._top_eigenvectors(A, C, rng)
            init = None
        else:
            cmin, cmax = int(self.min_clusters), min(int(self.max_clusters), n - 1)
            if not 2 <= cmin <= cmax:
                raise ValueError(f"need 2 <= min_clusters <= max_clusters < n_samples, got "
                                 f"{self.min_clusters}, {self.max_clusters}, n={n}")
            Uall = self._top_eigenvectors(A, cmax, rng)
            rotated = {}
            Z = Uall[:, :cmin]
            for C in range(cmin, cmax + 1):
                if C > cmin:
                    Z = np.column_stack([rotated[C - 1], Uall[:, C - 1]])
                cost, Zr = rotation_cost(Z, self.n_restarts, rng)
                self.rotation_costs_[C] = cost
                rotated[C] = Zr
            best = min(self.rotation_costs_.values())
            C = max(c for c, v in self.rotation_costs_.items() if v - best <= self.cost_tol)
            U = Uall[:, :C]
            lab0 = np.argmax(rotated[C] ** 2, axis=1)
            Un = normalize(U)
            init = np.array([Un[lab0 == c].mean(axis=0) if np.any(lab0 == c)
                             else Un[rng.randint(n)] for c in range(C)])
        Un = normalize(U)
        if C == 1:
            labels = np.zeros(n, dtype=int)
        elif init is not None:
            km = KMeans(C, init=init, n_init=1, random_state=rng).fit(Un)
            km2 = KMeans(C, n_init=10, random_state=rng).fit(Un)
            labels = (km if km.inertia_ <= km2.inertia_ else km2).labels_
        else:
            labels = KMeans(C, n_init=10, random_state=rng).fit(Un).labels_
        self.n_clusters_ = C
        self.labels_ = labels
        self.embedding_ = U
        return self


# ---------------------------------------------------------------------------------------------
# triplets

def _check_triplets(triplets, n):
    T = np.asarray(triplets)
    if T.size == 0:
        return np.zeros((0, 3), dtype=np.int64)
    if T.ndim != 2 or T.shape[1] != 3:
        raise ValueError(f"triplets must be an int array of shape (t, 3), got {T.shape}")
    if not np.issubdtype(T.dtype, np.integer):
        raise ValueError("triplets must hold integer shape indices")
    if n is not None and (T.min() < 0 or T.max() >= n):
        raise ValueError(f"triplet indices must be in [0, {n}), got range "
                         f"[{T.min()}, {T.max()}]")
    return T.astype(np.int64)


def must_cannot_from_triplets(triplets, n_samples=None):
    """Triplet (a, b, c) -> must-link (a, b) and cannot-link (a, c).

    Returns (must, cannot) as int arrays of unique unordered pairs (i < j), each (k, 2);
    self-pairs are dropped.
    """
    T = _check_triplets(triplets, n_samples)

    def pairs(P):
        P = P[P[:, 0] != P[:, 1]]
        P = np.sort(P, axis=1)
        return np.unique(P, axis=0) if len(P) else np.zeros((0, 2), dtype=np.int64)

    return pairs(T[:, [0, 1]]), pairs(T[:, [0, 2]])


class TripletClustering(ClusterMixin, BaseEstimator):
    """Triplet-constrained clustering, paper eq. 3: A' = A + N_m - N_c ~ Y S Y^T, Y >= 0.

    A is the cosine similarity of the fused features (rows L2-normalised), so its entries lie in
    [0, 1] for non-negative features, the same scale as the 0/1 constraint indicators; a pair that
    is both must- and cannot-linked cancels. A' has negative entries, so S is left free in sign
    (semi-NMF): S is the least-squares solution given Y, and Y takes the multiplicative update that
    splits the gradient into positive and negative parts (Ding, Li & Jordan). Y starts from k-means
    on the leading eigenvectors of A' (constraints included), plus 0.2 everywhere so no cluster
    is switched off. Labels are the row argmax of Y; ``membership_`` is Y with rows summing to one.
    """

    def __init__(self, n_clusters=2, random_state=None, max_iter=300, tol=1e-6):
        self.n_clusters = n_clusters
        self.random_state = random_state
        self.max_iter = max_iter
        self.tol = tol

    def fit(self, V, triplets=None):
        V = _check_features(V, "V")
        n = V.shape[0]
        C = int(self.n_clusters)
        if not 1 <= C <= n:
            raise ValueError(f"n_clusters must be in [1, {n}], got {self.n_clusters}")
        rng = check_random_state(self.random_state)
        Vn = normalize(V)
        A = Vn @ Vn.T
        if triplets is None:
            triplets = np.zeros((0, 3), dtype=np.int64)
        must, cannot = must_cannot_from_triplets(triplets, n)
        N = np.zeros((n, n))
        N[must[:, 0], must[:, 1]] += 1.0
        N[cannot[:, 0], cannot[:, 1]] -= 1.0
        N = N + N.T
        Ap = A + N
        self.similarity_ = Ap
        self.n_must_links_, self.n_cannot_links_ = len(must), len(cannot)

        w, U = eigh(Ap, subset_by_index=[n - C, n - 1])
        lab0 = KMeans(C, n_init=10, random_state=rng).fit_predict(normalize(U)) if C > 1 \
            else np.zeros(n, dtype=int)
        Y = np.full((n, C), 0.2)
        Y[np.arange(n), lab0] += 1.0

        def s_of(Y):
            G = np.linalg.pinv(Y.T @ Y)
            return G @ Y.T @ Ap @ Y @ G

        def obj(Y, S):
            return float(np.sum((Ap - Y @ S @ Y.T) ** 2))

        S = s_of(Y)
        history = [obj(Y, S)]
        eps = 1e-12
        n_iter = 0
        for n_iter in range(1, int(self.max_iter) + 1):
            AYS = Ap @ Y @ S
            YSYYS = Y @ (S @ (Y.T @ Y) @ S)
            num = np.maximum(AYS, 0) + np.maximum(-YSYYS, 0)
            den = np.maximum(-AYS, 0) + np.maximum(YSYYS, 0)
            Y = Y * np.sqrt((num + eps) / (den + eps))
            S = s_of(Y)
            history.append(obj(Y, S))
            if abs(history[-2] - history[-1]) <= self.tol * max(history[-2], eps):
                break
        self.S_ = S
        self.membership_ = Y / np.maximum(Y.sum(axis=1, keepdims=True), eps)
        self.labels_ = np.argmax(Y, axis=1)
        self.objective_history_ = np.array(history)
        self.n_iter_ = n_iter
        return self

    def fit_predict(self, V, triplets=None):
        return self.fit(V, triplets).labels_


# ---------------------------------------------------------------------------------------------
# style distance

def style_distance(V):
    """Pairwise style distance: cosine distance of the L2-normalised fused features (n x n)."""
    V = _check_features(V, "V")
    Vn = normalize(V)
    D = 1.0 - Vn @ Vn.T
    np.fill_diagonal(D, 0.0)
    return np.clip(D, 0.0, 2.0)


def predict_triplets(D, triplets):
    """For each triplet (a, b, c): True when d(a, b) < d(a, c), i.e. b is judged closer to a."""
    D = np.asarray(D, dtype=np.float64)
    if D.ndim != 2 or D.shape[0] != D.shape[1]:
        raise ValueError(f"D must be a square distance matrix, got shape {D.shape}")
    T = _check_triplets(triplets, D.shape[0])
    return D[T[:, 0], T[:, 1]] < D[T[:, 0], T[:, 2]]
