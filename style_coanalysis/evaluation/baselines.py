"""Baselines the method must beat: style guessed from global shape, raw size or plain line statistics.

If one of these already separates the styles of a collection, the collection (not the method) is
doing the work; the sample collection is built so the global-shape baseline stays near chance.
"""
from __future__ import annotations

import numpy as np
from skimage.filters import sobel_h, sobel_v
from sklearn.cluster import KMeans
from sklearn.preprocessing import StandardScaler

from ..meshes import face_areas, normalise

N_ORIENTATIONS = 8


def global_shape_features(meshes) -> np.ndarray:
    """(n, 4): two sorted bounding-box ratios (mid/long, short/long), face count and surface
    area after scaling into the unit sphere."""
    rows = []
    for m in meshes:
        n = normalise(m)
        e = np.sort(np.ptp(n.vertices.astype(np.float64), axis=0))[::-1]
        rows.append([e[1] / e[0], e[2] / e[0], len(n.faces), face_areas(n.vertices, n.faces).sum()])
    return np.asarray(rows, dtype=np.float64)


def raw_size(meshes_raw) -> np.ndarray:
    """(n, 4): log of the bounding-box diagonal and of the sorted extents, before any normalising
    (a collection whose styles come from different sources often differs in units)."""
    rows = []
    for m in meshes_raw:
        e = np.sort(np.ptp(m.vertices.astype(np.float64), axis=0))[::-1]
        rows.append(np.log(np.maximum(np.r_[np.linalg.norm(e), e], 1e-12)))
    return np.asarray(rows)


def _view_stats(img: np.ndarray) -> np.ndarray:
    """Ink density and a magnitude-weighted, unsigned orientation histogram of one drawing."""
    img = np.asarray(img, dtype=np.float64)
    gy, gx = sobel_h(img), sobel_v(img)
    mag = np.hypot(gx, gy)
    ang = np.mod(np.arctan2(gy, gx), np.pi)
    hist, _ = np.histogram(ang, bins=N_ORIENTATIONS, range=(0, np.pi), weights=mag)
    total = hist.sum()
    return np.r_[img.mean(), hist / total if total > 0 else hist]


def line_statistics(images_per_shape, per_view: bool = False) -> np.ndarray:
    """Whole-image statistics of each shape's line drawings ((V, H, W), 1 = ink): averaged over
    the views (azimuth-free) or, with per_view, concatenated in view order."""
    rows = []
    for views in images_per_shape:
        stats = np.stack([_view_stats(v) for v in np.asarray(views)])
        rows.append(stats.ravel() if per_view else stats.mean(axis=0))
    return np.asarray(rows)


def cluster_baseline(features, n_clusters: int, seed: int = 0) -> np.ndarray:
    """Standardise each feature, then k-means: labels (n,)."""
    X = StandardScaler().fit_transform(np.asarray(features, dtype=np.float64))
    return KMeans(n_clusters=n_clusters, n_init=10, random_state=seed).fit_predict(X)
