"""Style regions on the surface (paper 4.5, "Style patch extraction") and style-aware best view.

The style filters of a cluster are words of the shared dictionary (line patterns, the same for
every view). To find where a shape carries its cluster's style, every inked window of every one
of its drawings is matched to its most similar word of the WHOLE dictionary (the same assignment
the encoding counts); a window is a style window when that word is a style filter of the shape's
cluster and the similarity reaches `threshold`. Matching against the whole dictionary, not just
the style filters, is what keeps generic corners and edges out: they are claimed by the generic
words. This dense matching extends the paper's seed patches to regions (its decimation
application took three times as many seeds for the same purpose): every window position is a
candidate, so regions are not limited to where 30 or 90 seeds happened to fall.

Which surface the style windows mark is decided per face by `regions` (the windows' cover and
the carved regions their strokes lie in); a vertex's weight, the `style_weight` group, is the
area-weighted mean of its faces' weights. Best view: the view with the most style windows (ties:
the larger summed similarity).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import regions
from .drawings import ShapeDrawings
from .encoding import word_assignments
from .features import PIXELS_PER_CELL, hog_images
from .meshes import face_areas

MAX_BOXES_PER_VIEW = 12      # style windows kept per view for the report's boxes


@dataclass
class ShapeLocalisation:
    weights: np.ndarray          # (N,) float32 in [0, 1], per mesh vertex
    face_weights: np.ndarray     # (M,) float32 in [0, 1], per triangle; > 0.5: style region
    best_view: int
    matches: list                # (view, x, y, similarity) of the strongest style windows
    view_scores: np.ndarray      # (V,) style windows per view


def style_windows(maps: np.ndarray, words: np.ndarray, word_cluster: np.ndarray, cluster: int,
                  threshold: float):
    """(V, oy, ox) bool style windows of one shape, and their similarities."""
    best, sim, inked = word_assignments(maps, words)
    style = inked & (np.asarray(word_cluster)[best] == cluster) & (sim >= threshold)
    return style, sim


def coverage(style: np.ndarray, patch_size: int, image_size: int) -> np.ndarray:
    """(V, H, W) bool: pixels covered by at least one style window (window (r, c) starts at
    pixel (8r, 8c) and spans patch_size pixels, as `features.patch_block_origins` aligns it)."""
    v, oy, ox = style.shape
    hits = np.zeros((v, image_size + 1, image_size + 1), np.int32)
    vv, rr, cc = np.nonzero(style)
    r0, c0 = rr * PIXELS_PER_CELL, cc * PIXELS_PER_CELL
    r1, c1 = np.minimum(r0 + patch_size, image_size), np.minimum(c0 + patch_size, image_size)
    # summed-area trick: +1/-1 at the rectangle corners, then cumulative sums
    np.add.at(hits, (vv, r0, c0), 1)
    np.add.at(hits, (vv, r0, c1), -1)
    np.add.at(hits, (vv, r1, c0), -1)
    np.add.at(hits, (vv, r1, c1), 1)
    return hits.cumsum(axis=1).cumsum(axis=2)[:, :image_size, :image_size] > 0


def localise_shape(drawings: ShapeDrawings, vertices: np.ndarray, faces: np.ndarray,
                   words: np.ndarray, word_cluster: np.ndarray, cluster: int, patch_size: int,
                   threshold: float, maps: np.ndarray | None = None,
                   region_params: regions.RegionParams = regions.RegionParams()) -> ShapeLocalisation:
    """Per-face and per-vertex style weights and best view of one shape in style cluster
    `cluster` (vertices in the normalised frame the drawings were made in)."""
    size = drawings.images.shape[-1]
    if maps is None:
        maps = hog_images(drawings.images)
    style, sim = style_windows(maps, words, word_cluster, cluster, threshold)
    cover = coverage(style, patch_size, size)
    face_w = regions.face_weights(vertices, faces, drawings.cameras, drawings.images, cover,
                                  region_params)
    weights = regions.vertex_weights(face_w, faces, face_areas(vertices, faces), len(vertices))
    counts = style.sum(axis=(1, 2))
    sims = np.where(style, sim, 0.0).sum(axis=(1, 2))
    best = int(np.lexsort((sims, counts))[-1])
    matches = []
    half = patch_size / 2.0
    for v in range(drawings.n_views):
        rr, cc = np.nonzero(style[v])
        order = np.argsort(-sim[v, rr, cc], kind="stable")[:MAX_BOXES_PER_VIEW]
        matches += [(v, float(cc[k] * PIXELS_PER_CELL + half), float(rr[k] * PIXELS_PER_CELL + half),
                     float(sim[v, rr[k], cc[k]])) for k in order]
    return ShapeLocalisation(weights, face_w, best, matches, counts)


def top_words(word_cluster: np.ndarray, word_score: np.ndarray, per_cluster: int) -> np.ndarray:
    """word_cluster keeping only each cluster's `per_cluster` best-scoring style words (-1 else).

    Reselection keeps every word that discriminates a cluster at all (enough to cluster well);
    marking regions wants only the most characteristic ones, or plain surface near any
    slightly cluster-typical line gets marked too."""
    out = np.full_like(np.asarray(word_cluster), -1)
    for c in np.unique(word_cluster[word_cluster >= 0]):
        ws = np.flatnonzero(word_cluster == c)
        ws = ws[np.argsort(-np.asarray(word_score)[ws], kind="stable")][:per_cluster]
        out[ws] = c
    return out
