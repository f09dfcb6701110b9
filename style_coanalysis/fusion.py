"""Feature fusions to compare against the default style graph and PSLF on the same views.

Each takes the list of views (n_samples, n_features_p) and returns one (n_samples, d) matrix. All
start from :func:`style_coanalysis.scaling.scale_views`, the scaling PSLF uses, so a comparison
measures the fusion, not the pre-processing.
"""
from __future__ import annotations

from itertools import combinations

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.cross_decomposition import CCA
from sklearn.decomposition import PCA
from sklearn.preprocessing import StandardScaler

from .scaling import scale_views


class ConcatFusion(BaseEstimator):
    """Concatenation of the scaled views (each view has unit energy, so equal say)."""

    def __init__(self, scaling="auto"):
        self.scaling = scaling

    def fit_transform(self, views, y=None):
        Xs = scale_views(views, self.scaling)
        self.n_features_per_view_ = [X.shape[1] for X in Xs]
        return np.hstack(Xs)

    def fit(self, views, y=None):
        self.fit_transform(views)
        return self


class PCAFusion(BaseEstimator):
    """PCA of the concatenated views, each feature standardised (z-score) first."""

    def __init__(self, n_components=20, scaling="auto", random_state=None):
        self.n_components = n_components
        self.scaling = scaling
        self.random_state = random_state

    def fit_transform(self, views, y=None):
        Xc = np.hstack(scale_views(views, self.scaling))
        Z = StandardScaler().fit_transform(Xc)
        k = min(int(self.n_components), *Z.shape)
        self.pca_ = PCA(k, random_state=self.random_state)
        return self.pca_.fit_transform(Z)

    def fit(self, views, y=None):
        self.fit_transform(views)
        return self


class CCAFusion(BaseEstimator):
    """CCA of the pair of views that correlate best (chosen without labels).

    Every pair is scored by its first canonical correlation (after a PCA to at most
    ``max_pca`` dims per view, which keeps CCA well posed when views have more features than
    shapes); the chosen pair's canonical variates of both views are concatenated.
    """

    def __init__(self, n_components=10, scaling="auto", max_pca=30, random_state=None):
        self.n_components = n_components
        self.scaling = scaling
        self.max_pca = max_pca
        self.random_state = random_state

    def _reduce(self, X):
        Z = StandardScaler().fit_transform(X)
        k = min(int(self.max_pca), Z.shape[1], Z.shape[0] - 1)
        return PCA(k, random_state=self.random_state).fit_transform(Z)

    def fit_transform(self, views, y=None):
        Xs = scale_views(views, self.scaling)
        if len(Xs) < 2:
            raise ValueError("CCAFusion needs at least two views")
        R = [self._reduce(X) for X in Xs]
        scores = {}
        for i, j in combinations(range(len(R)), 2):
            cca = CCA(n_components=1, max_iter=1000).fit(R[i], R[j])
            a, b = cca.transform(R[i], R[j])
            scores[(i, j)] = float(abs(np.corrcoef(a[:, 0], b[:, 0])[0, 1]))
        self.pair_scores_ = scores
        self.best_pair_ = max(scores, key=scores.get)
        i, j = self.best_pair_
        k = min(int(self.n_components), R[i].shape[1], R[j].shape[1])
        self.cca_ = CCA(n_components=k, max_iter=1000).fit(R[i], R[j])
        a, b = self.cca_.transform(R[i], R[j])
        return np.hstack([a, b])

    def fit(self, views, y=None):
        self.fit_transform(views)
        return self
