"""Style patches on the surface (paper 4.5, "Style patch extraction") and style-aware best view.

The style filters of a cluster are real patches of a few shapes. To find style on every member
of the cluster, each of its seeds' patches (three times as many seeds as the analysis used, as in
the paper's decimation application) is compared with the cluster's style filters in HOG space
(cosine of the block histograms, the same similarity the encoding uses). A patch that reaches
`match_threshold` marks its footprint: the mesh vertices seen in that view that project inside
the patch window and lie near the seed in 3D (so a surface far behind the window is not taken).
A fixed similarity threshold alone marks almost every patch (line drawings share a lot of
generic corners and edges), so a patch must also be closer to its own cluster's style filters
than to the other clusters' ones: it must look like *this* style, not like style in general.

A vertex's style weight is the share of the views that see it in which it was marked: 1 means
"style-bearing from every side it can be seen", 0 "never". Best view: the view with the most
matched patches (ties: the larger summed similarity).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .drawings import ShapeDrawings
from .features import hog_images, patch_descriptors
from .rig import project

EPS = 1e-6


@dataclass
class ShapeLocalisation:
    weights: np.ndarray          # (N,) float32 in [0, 1], per mesh vertex
    best_view: int
    matches: list                # (view, x, y, similarity) of every matched patch
    view_scores: np.ndarray      # (V,) matched patches per view


def _unit(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, np.float32).reshape(len(x), -1)
    return x / np.maximum(np.linalg.norm(x, axis=1, keepdims=True), EPS)


def footprint(vertices: np.ndarray, pixels: np.ndarray, depth: np.ndarray, visible: np.ndarray,
              seed_point: np.ndarray, seed_pixel: np.ndarray, seed_depth: float,
              half: float, focal: float) -> np.ndarray:
    """Vertices (bool mask) visible in this view, inside the window, and near the seed in 3D.

    The 3D radius is the window's half-diagonal at the seed's depth: a patch covers that much
    surface around its seed, no more.
    """
    inside = (np.abs(pixels[:, 0] - seed_pixel[0]) <= half) & \
             (np.abs(pixels[:, 1] - seed_pixel[1]) <= half)
    radius = np.sqrt(2.0) * half * seed_depth / focal
    near = np.linalg.norm(vertices - seed_point, axis=1) <= radius
    return visible & inside & near


def localise_shape(drawings: ShapeDrawings, vertices: np.ndarray, filters: np.ndarray,
                   patch_size: int, threshold: float, focal: float,
                   maps: np.ndarray | None = None, others: np.ndarray | None = None,
                   ) -> ShapeLocalisation:
    """Per-vertex style weights of one shape from its cluster's style filters (F, ...);
    `others` are the other clusters' style filters, which a match must be closer to."""
    n_views = drawings.n_views
    n_vert = len(vertices)
    if maps is None:
        maps = hog_images(drawings.images)
    vpix, vdepth = project(drawings.cameras, vertices)
    spix, sdepth = project(drawings.cameras, drawings.seeds)
    marked = np.zeros((n_views, n_vert), bool)
    view_scores = np.zeros(n_views)
    view_sims = np.zeros(n_views)
    matches = []
    unit_filters = _unit(filters) if len(filters) else np.zeros((0, 1), np.float32)
    unit_others = _unit(others) if others is not None and len(others) else None
    half = patch_size / 2.0
    for v in range(n_views):
        seeds = np.flatnonzero(drawings.seed_visible[v])
        if len(seeds) == 0 or len(unit_filters) == 0:
            continue
        desc, _ = patch_descriptors(maps, np.full(len(seeds), v), drawings.seed_pixels[v, seeds],
                                    patch_size)
        desc = _unit(desc)
        sim = (desc @ unit_filters.T).max(axis=1)
        ok = sim >= threshold
        if unit_others is not None:
            ok &= sim > (desc @ unit_others.T).max(axis=1)
        for j, s in zip(seeds[ok], sim[ok]):
            marked[v] |= footprint(vertices, vpix[v], vdepth[v], drawings.vertex_visible[v],
                                   drawings.seeds[j], spix[v, j], sdepth[v, j], half, focal)
            matches.append((v, float(spix[v, j, 0]), float(spix[v, j, 1]), float(s)))
        view_scores[v] = int(ok.sum())
        view_sims[v] = float(sim[ok].sum())
    seen = drawings.vertex_visible.sum(axis=0)
    weights = np.where(seen > 0, marked.sum(axis=0) / np.maximum(seen, 1), 0.0).astype(np.float32)
    best = int(np.lexsort((view_sims, view_scores))[-1])
    return ShapeLocalisation(weights, best, matches, view_scores)


def cluster_filters(style_filters, cluster: int) -> tuple[np.ndarray, np.ndarray | None]:
    """(the HOG filters that discriminate `cluster`, the other clusters' filters or None).

    A cluster with no filter of its own falls back to all style filters with no contrast set.
    """
    own = [f.hog for f in style_filters if f.cluster == cluster]
    other = [f.hog for f in style_filters if f.cluster != cluster]
    if not own:
        own, other = [f.hog for f in style_filters], []
    empty = np.zeros((0, 1), np.float32)
    return (np.asarray(own, np.float32) if own else empty,
            np.asarray(other, np.float32) if other else None)


def face_weights(weights: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Per-face style weight: the mean of its vertices' weights."""
    return np.asarray(weights)[faces].mean(axis=1)
