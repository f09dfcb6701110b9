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
whole collection, and lets the fusion keep what they agree on.
The ladder spans the same fractions of every collection: N, N/2, ... N/16 (`LADDER_RUNGS` = 5), and
not below MIN_NEIGHBOURS. Halving on down to a handful added a rung per doubling of N, and on a
large collection those rungs compare a shape with near copies of itself, which cancels its style
with its build: on hu2017-all (537 real pieces of furniture, k given, seed 0) each rung alone
reached style purity 0.48 / 0.54 / 0.61 / 0.47 at 536 / 268 / 134 / 67 look-alikes but 0.41 /
0.37 / 0.34 / 0.33 at 34 / 17 / 8 / 4 (chance 0.28), and all eight fused gave 0.44, below
line statistics' 0.46. The five top rungs (3 seeds, the benchmark's encodings): k given
0.435 -> 0.580, 2 labels 0.437 -> 0.590, automatic k 0.395 -> 0.457. sample-240, whose
ladder loses its rung of 7: 0.965 / 0.967 / 0.746 -> 0.961 / 0.963 / 0.746. Four rungs (to
N/8) also fixed hu2017-all's automatic k (0.583, 4 clusters) but lost 0.01-0.03 on sample-240 and
collection2 with k given and 2 labels. Collections of at most 128 shapes had at most five rungs
already: their views are unchanged.
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
from sklearn.metrics import pairwise_distances

MIN_NEIGHBOURS = 4        # the smallest rung: fewer look-alikes estimate a mean profile from noise
LADDER_RUNGS = 5          # rungs of the ladder: N - 1 down to N / 16
RUNG_SAMPLE = 64          # a rung's mean profile is read off this many of its look-alikes at most
BLOCK = 256               # rows of the distance matrix held at once


def neighbour_ladder(n: int) -> list[int]:
    """Neighbour counts n-1, n/2, n/4, ...: `LADDER_RUNGS` of them, none below MIN_NEIGHBOURS
    (at least the first)."""
    ks, k = [], float(n - 1)
    while (k >= MIN_NEIGHBOURS and len(ks) < LADDER_RUNGS) or not ks:
        ks.append(max(1, int(round(k))))
        k /= 2
    return ks


def look_alikes(layout: np.ndarray, k: int) -> np.ndarray:
    """(N, k) each shape's k nearest structural neighbours (nearest first, itself excluded).

    `layout`: the shapes' profiles over large (layout-scale) patches, standardised here. Built in
    row blocks, so memory grows with N*k, not N^2 times the profile length; ties in distance
    break by position (tied shapes are exact duplicates, whose profiles are equal)."""
    s = np.asarray(layout, np.float64)
    s = (s - s.mean(axis=0)) / (s.std(axis=0) + 1e-9)
    n = len(s)
    k = int(min(k, n - 1))
    out = np.empty((n, k), np.int64)
    for start in range(0, n, BLOCK):
        stop = min(n, start + BLOCK)
        d2 = pairwise_distances(s[start:stop], s, metric="sqeuclidean")
        d2[np.arange(stop - start), np.arange(start, stop)] = -1.0        # itself first
        near = np.argpartition(d2, k, axis=1)[:, :k + 1] if k + 1 < n else \
            np.broadcast_to(np.arange(n), d2.shape).copy()
        near = np.take_along_axis(near, np.argsort(np.take_along_axis(d2, near, 1), axis=1,
                                                   kind="stable"), 1)
        out[start:stop] = near[:, 1:k + 1]
    return out


def rung_ranks(k: int) -> np.ndarray:
    """The ranks (0 = nearest) whose profiles make a rung's mean: all k up to RUNG_SAMPLE, else
    RUNG_SAMPLE spread evenly over the k nearest. The ladder's top rungs hold N/2, N/4, ...
    look-alikes; averaging all of them cost N^2 per collection (24x per shape at 5,000 shapes
    against 120), and an even sample by rank keeps the rung's spread of near and far
    look-alikes at a cost that stays flat per shape."""
    if k <= RUNG_SAMPLE:
        return np.arange(k)
    return np.round(np.linspace(0, k - 1, RUNG_SAMPLE)).astype(np.int64)


def structure_relative(words: np.ndarray, neighbours: np.ndarray, ks) -> list[np.ndarray]:
    """Each shape's word profile minus the mean profile of its k nearest structural neighbours
    (`rung_ranks` of them), for every k in `ks` (`neighbours` from `look_alikes`, at least
    max(ks) of them per shape; k >= N-1 is plain centring on the collection mean). In row
    blocks."""
    words = np.asarray(words, np.float64)
    n = len(words)
    out = [np.empty_like(words) for _ in ks]
    inner = [i for i, k in enumerate(ks) if k < n - 1]
    for i, k in enumerate(ks):
        if k >= n - 1:
            out[i] = words - words.mean(axis=0)
    if inner:
        ranks = [rung_ranks(ks[i]) for i in inner]
        step = max(1, int(2 ** 22 // max(1, RUNG_SAMPLE * words.shape[1])))   # ~32 MB gathered
        for start in range(0, n, step):
            stop = min(n, start + step)
            near = neighbours[start:stop]
            for i, r in zip(inner, ranks):
                out[i][start:stop] = words[start:stop] - words[near[:, r]].mean(axis=1)
    return out


def style_space(x: np.ndarray, n_dims: int) -> np.ndarray:
    """Standardise features, keep the principal subspace, unit rows: (N, d).

    Standardising lets rare ornament words count as much as frequent ones; the principal
    directions keep what many features vary along together (a style is a set of ornaments
    that occur together); unit rows make distances compare directions. The principal directions
    come from the (K, K) covariance rather than an SVD of the (N, K) rows: the same subspace
    (distances between rows do not see a direction's sign), several times faster for N >> K."""
    x = np.asarray(x, np.float64)
    x = (x - x.mean(axis=0)) / (x.std(axis=0) + 1e-9)
    d = int(min(n_dims, x.shape[1], max(len(x) - 1, 1)))
    p = PCA(d, svd_solver="covariance_eigh").fit_transform(x) if d >= 1 else x
    return p / np.maximum(np.linalg.norm(p, axis=1, keepdims=True), 1e-12)


def word_views(rungs: list, keep: np.ndarray, n_dims: int) -> tuple[list, list]:
    """The word views of one dictionary and their names: one structure-relative word view per
    rung of the neighbour ladder (`rungs`: structure_relative over `neighbour_ladder(N)`),
    each restricted to the kept words and put in its `n_dims` principal directions
    (style_space). A rung's relative profile is linear in each word, so the kept words' columns
    are the profile of the kept words: the rungs are computed once per encoding, not per round.
    The pipeline adds the line-character view."""
    views = [style_space(r[:, keep], n_dims) for r in rungs]
    return views, [f"words vs {k} look-alikes" for k in neighbour_ladder(len(rungs[0]))]
