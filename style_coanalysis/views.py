"""The views the default method fuses: what a shape's lines say about style, seen several ways.

Style is what recurs across structurally different shapes. A shape's small-patch word profile
(encoding.frequency_features) mixes its style with its build: a bed has long rails whatever its
ornament. Subtracting the mean profile of the shape's structural look-alikes (neighbours in a
layout space of large patches) leaves what the shape has *more* than its look-alikes: ornament.
How many look-alikes to compare with depends on the collection: a few when categories are many
and large, all of them when there is one category, and in a real collection whose layout itself
carries style (a cabriole chair's outline), comparing with too few cancels the style. Measured on
the sample (k-means, k given): 1/6 of the shapes as neighbours gave 0.97 style purity on all 240
shapes but 0.78 on a single category, where comparing with all of them gave 0.97; on real
furniture the opposite order held (0.76 at 1/6, 0.96 at 1/2). No one count holds everywhere, so
the method does not pick one: it builds one view per scale of a ladder that halves from the
whole collection down to a handful of neighbours, and lets the fusion keep what they agree on.
The ladder's smallest rung (MIN_NEIGHBOURS = 4), measured with k given on seven benchmark
collections: 8 -> 4 raised sample-120 0.68 -> 0.80, collection2 0.56 -> 0.63, sample-24
0.54 -> 0.71, sample-styles-2 0.79 -> 0.85, sample-cats-1 0.79 -> 0.81, kept hu2017-60-1 at
0.60 and lowered hu2017-60-0 0.55 -> 0.52 (two shapes); 3 gave about the same on the samples and
lost more on the voxel sets.
A last view describes the line character of the drawings (line_character): how curved, how
oriented, how dense the lines are, independent of any dictionary.
"""
from __future__ import annotations

import numpy as np
from sklearn.decomposition import PCA
from sklearn.neighbors import NearestNeighbors

MIN_NEIGHBOURS = 4        # the smallest rung: fewer look-alikes estimate a mean profile from noise


def neighbour_ladder(n: int) -> list[int]:
    """Neighbour counts n-1, n/2, n/4, ... down to MIN_NEIGHBOURS (at least the first)."""
    ks, k = [], float(n - 1)
    while k >= MIN_NEIGHBOURS or not ks:
        ks.append(max(1, int(round(k))))
        k /= 2
    return ks


def structure_relative(words: np.ndarray, layout: np.ndarray, k: int) -> np.ndarray:
    """Each shape's word profile minus the mean profile of its k nearest structural neighbours.

    `layout`: the shapes' profiles over large (layout-scale) patches, standardised here. With
    k >= n-1 this is plain centring on the collection mean. Ties in distance break by the
    neighbours' layout values, not their position in the list, so the order of the input does
    not matter."""
    words = np.asarray(words, np.float64)
    n = len(words)
    if k >= n - 1:
        return words - words.mean(axis=0)
    s = np.asarray(layout, np.float64)
    s = (s - s.mean(axis=0)) / (s.std(axis=0) + 1e-9)
    nn = NearestNeighbors(n_neighbors=k + 1).fit(s).kneighbors(s, return_distance=False)
    own = nn == np.arange(n)[:, None]
    # drop the shape itself (or, if duplicates pushed it out, the farthest neighbour)
    keep = np.where(own.any(axis=1, keepdims=True), ~own, np.arange(k + 1) < k)
    idx = nn[keep].reshape(n, k)
    return words - words[idx].mean(axis=1)


def style_space(x: np.ndarray, n_dims: int) -> np.ndarray:
    """Standardise features, keep the principal subspace, unit rows: (N, d).

    Standardising lets rare ornament words count as much as frequent ones; the principal
    directions keep what many features vary along together (a style is a set of ornaments
    that occur together); unit rows make distances compare directions."""
    x = np.asarray(x, np.float64)
    x = (x - x.mean(axis=0)) / (x.std(axis=0) + 1e-9)
    d = int(min(n_dims, x.shape[1], max(len(x) - 1, 1)))
    p = PCA(d, svd_solver="full").fit_transform(x) if d >= 1 else x
    return p / np.maximum(np.linalg.norm(p, axis=1, keepdims=True), 1e-12)


def fusion_views(words: np.ndarray, layout: np.ndarray, lines: np.ndarray,
                 n_dims: int) -> tuple[list, list]:
    """The default method's views and their names: one structure-relative word view per rung of
    the neighbour ladder, then the line-character view; each in its `n_dims` principal
    directions (style_space)."""
    n = len(words)
    views, names = [], []
    for k in neighbour_ladder(n):
        views.append(style_space(structure_relative(words, layout, k), n_dims))
        names.append(f"words vs {k} look-alikes")
    views.append(style_space(lines, n_dims))
    names.append("line character")
    return views, names
