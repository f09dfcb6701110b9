"""Representative patches and convolutional view encoding (paper 4.1 end, 4.2).

Representatives: per view, k-means over the HOG descriptors of all patches seen in that view;
each centre is replaced by the real patch nearest to it, so that every filter is a patch one can
show and back-project (it remembers shape, view, seed and pixel).

Encoding: each filter is slid over the HOG map of the view it came from (in every shape), and the
response is max-pooled over the whole image and over its four quadrants: 5 numbers per filter.

Response = cosine similarity between the filter and the local map window (both as vectors of
block histograms). Why cosine rather than a raw dot product: the HOG blocks are already
L2-normalised, so a raw dot product grows with the number of non-empty blocks in the window,
and a dense tangle of lines would answer every filter. Dividing by both norms leaves only the
agreement of orientation patterns. Why not mean-centred NCC: cosine of non-negative vectors is
in [0, 1], and the next stage (PSLF, a non-negative factorisation) needs non-negative input;
and centring on the collection's mean window was tried and separated the synthetic styles worse
(blank and outline windows dominate the mean).

Vectorised as im2col: the windows of a batch of maps are gathered with a strided view and
multiplied by the (unit) filter matrix in one product per chunk; no Python loop over positions.
A window is assigned to a quadrant by its centre pixel.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from sklearn.cluster import KMeans, MiniBatchKMeans

from .features import PIXELS_PER_CELL

EPS = 1e-6
N_POOL = 5          # whole image + 4 quadrants
MINIBATCH_ABOVE = 6000   # k-means on more descriptors than this uses MiniBatchKMeans


@dataclass
class FilterBank:
    """Representative patches used as filters; row f of every array describes filter f."""

    hog: np.ndarray       # (F, nb, nb, C) float32, unit L2 norm
    view: np.ndarray      # (F,) int view the filter was picked in (and is applied to)
    shape: np.ndarray     # (F,) int source shape index
    seed: np.ndarray      # (F,) int source seed index
    pixel: np.ndarray     # (F, 2) float32 (x, y) centre of the source patch

    def __len__(self) -> int:
        return int(len(self.hog))

    def subset(self, index) -> "FilterBank":
        return FilterBank(self.hog[index], self.view[index], self.shape[index], self.seed[index],
                          self.pixel[index])


def unit_rows(x: np.ndarray) -> np.ndarray:
    """Rows scaled to unit L2 norm (all-zero rows stay zero)."""
    x = np.asarray(x, np.float32).reshape(len(x), -1)
    norm = np.linalg.norm(x, axis=1, keepdims=True)
    return x / np.maximum(norm, EPS)


def representatives(descriptors: np.ndarray, k: int, random_state: int = 0) -> np.ndarray:
    """Indices of up to `k` real patches, one per k-means centre, nearest to their centre.

    Clustering runs on unit-normalised descriptors, matching the cosine used in encoding.
    Fewer than `k` are returned when there are fewer distinct descriptors.
    """
    x = unit_rows(descriptors)
    n = len(x)
    if n == 0 or k <= 0:
        return np.zeros(0, np.int64)
    n_distinct = len(np.unique(x.round(5), axis=0))
    k = min(k, n_distinct)
    if k == n:
        return np.arange(n)
    if n > MINIBATCH_ABOVE:
        km = MiniBatchKMeans(n_clusters=k, n_init=1, batch_size=2048, random_state=random_state)
    else:
        km = KMeans(n_clusters=k, n_init=1, random_state=random_state)   # k-means++ start; one run
    labels = km.fit_predict(x)
    d2 = ((x - km.cluster_centers_[labels]) ** 2).sum(axis=1)
    chosen = []
    for c in range(k):
        members = np.flatnonzero(labels == c)
        if len(members):
            chosen.append(members[np.argmin(d2[members])])
    return np.sort(np.asarray(chosen, np.int64))


def correlate_pooled(maps: np.ndarray, filters: np.ndarray, image_size: tuple[int, int],
                     chunk_values: int = 12_000_000) -> np.ndarray:
    """Cosine responses of every filter over every map, max-pooled: (M, K, 5).

    maps: (M, by, bx, C) HOG block maps; filters: (K, nb, nb, C). Pool order: whole image, then
    quadrants top-left, top-right, bottom-left, bottom-right (by window centre pixel).
    """
    maps = np.asarray(maps, np.float32)
    filters = np.asarray(filters, np.float32)
    m, by, bx, c = maps.shape
    k, nb = len(filters), filters.shape[1]
    oy, ox = by - nb + 1, bx - nb + 1
    out = np.zeros((m, k, N_POOL), np.float32)
    if m == 0 or k == 0 or oy <= 0 or ox <= 0:
        return out
    # sliding_window_view puts the window axes last: (M, oy, ox, C, nb, nb); match the filters
    fmat = unit_rows(filters.transpose(0, 3, 1, 2)).T                                          # (C*nb*nb, K)
    h, w = image_size
    centre = (np.arange(oy) + (nb + 1) / 2) * PIXELS_PER_CELL
    top = centre < h / 2
    centre_x = (np.arange(ox) + (nb + 1) / 2) * PIXELS_PER_CELL
    left = centre_x < w / 2
    quads = [(top, left), (top, ~left), (~top, left), (~top, ~left)]
    step = max(1, chunk_values // (oy * ox * c * nb * nb))
    for s in range(0, m, step):
        win = sliding_window_view(maps[s:s + step], (nb, nb), axis=(1, 2))
        cols = win.reshape(-1, c * nb * nb)                              # copy: (b*oy*ox, D)
        norm = np.sqrt(np.einsum("ij,ij->i", cols, cols))
        resp = (cols @ fmat) / np.maximum(norm, EPS)[:, None]
        resp[norm < EPS] = 0.0
        resp = resp.reshape(-1, oy, ox, k)
        out[s:s + step, :, 0] = resp.max(axis=(1, 2))
        for q, (rows, colsel) in enumerate(quads, start=1):
            if rows.any() and colsel.any():
                out[s:s + step, :, q] = resp[:, rows][:, :, colsel].max(axis=(1, 2))
    return np.clip(out, 0.0, 1.0)


def encode(view_maps: np.ndarray, bank: FilterBank, image_size: tuple[int, int]) -> np.ndarray:
    """Pooled responses of each filter over its own view in every shape: (N, F, 5).

    view_maps: (N, V, by, bx, C). Each view's filters run only on that view of each shape, so
    the per-view feature of view v is `pooled[:, bank.view == v].reshape(N, -1)` (5K values).
    """
    n = view_maps.shape[0]
    out = np.zeros((n, len(bank), N_POOL), np.float32)
    for v in np.unique(bank.view):
        idx = np.flatnonzero(bank.view == v)
        out[:, idx] = correlate_pooled(view_maps[:, v], bank.hog[idx], image_size)
    return out


def view_features(pooled: np.ndarray, bank_view: np.ndarray, keep: np.ndarray | None,
                  n_views: int) -> list[np.ndarray]:
    """Per-view feature matrices (N, 5 K_v) from pooled responses, using only the kept filters.

    Re-encoding with a subset of filters is exactly this column selection, so it costs nothing.
    """
    n = pooled.shape[0]
    keep = np.ones(len(bank_view), bool) if keep is None else np.asarray(keep, bool)
    return [pooled[:, keep & (bank_view == v)].reshape(n, -1) for v in range(n_views)]


def cross_view_responses(view_maps: np.ndarray, bank: FilterBank,
                         image_size: tuple[int, int]) -> np.ndarray:
    """Whole-image max response of every filter in every view of every shape: (N, V, F)."""
    n, v = view_maps.shape[:2]
    flat = view_maps.reshape(n * v, *view_maps.shape[2:])
    return correlate_pooled(flat, bank.hog, image_size)[:, :, 0].reshape(n, v, len(bank))


def build_filter_bank(view_maps: np.ndarray, shape: np.ndarray, view: np.ndarray,
                      seed: np.ndarray, centre: np.ndarray, size: int, k: int,
                      random_state: int = 0) -> FilterBank:
    """Representative filters of every view from the collection's patches.

    view_maps: (N, V, by, bx, C); shape, view, seed: (n,) per patch; centre: (n, 2) (x, y).
    Descriptors are cut from the maps (features.patch_descriptors), so each filter is exactly
    a window of its source view's map. Windows with no gradient at all are ignored.
    """
    from .features import patch_descriptors

    n_shapes, n_views = view_maps.shape[:2]
    shape = np.asarray(shape, np.int64)
    view = np.asarray(view, np.int64)
    flat = view_maps.reshape(n_shapes * n_views, *view_maps.shape[2:])
    desc, _ = patch_descriptors(flat, shape * n_views + view, centre, size)
    nonblank = desc.reshape(len(desc), -1).max(axis=1) > EPS if len(desc) else np.zeros(0, bool)
    picks = []
    for v in range(n_views):
        idx = np.flatnonzero((view == v) & nonblank)
        if len(idx):
            picks.append(idx[representatives(desc[idx], k, random_state + v)])
    pick = np.concatenate(picks) if picks else np.zeros(0, np.int64)
    hogs = unit_rows(desc[pick]).reshape(desc[pick].shape) if len(pick) else desc[:0]
    return FilterBank(hogs.astype(np.float32), view[pick], shape[pick],
                      np.asarray(seed, np.int64)[pick], np.asarray(centre, np.float32)[pick])


# --------------------------------------------------------------------------------------------
# Frequency encoding with one dictionary shared by all views (what the analysis uses now).
#
# Why these departures from the per-view, max-pooled, quadrant-pooled encoding above, measured
# on the 120-shape sample (Freestyle, 30 seeds; k-means k=4 purity unless said otherwise):
# * Shared dictionary: the shapes are upright but not azimuth-aligned, so view v of two shapes
#   shows different sides; a per-view dictionary splits one ornament into 12 unrelated filters.
# * Frequency ("bag of patches") pooling: the count of inked windows whose best filter is f.
#   Max pooling saturates (every drawing has some window that half-matches every filter): with
#   true-category centring (an oracle, to measure what the encoding holds) max pooling gave 0.45
#   style purity, frequency pooling 0.46 at 48 px and 0.89 at 24 px.
# * Quadrant pooling dropped: it encodes where lines are, i.e. layout, i.e. category.
# * Small patches (24 px = 3x3 cells = 2x2 blocks): ornaments are small at 200 px; 48 px windows
#   are dominated by the part layout around them (see the purities above).
# Each filter is still a real patch (nearest to its k-means centre), slid over HOG maps.


def shared_bank(view_maps: np.ndarray, shape: np.ndarray, view: np.ndarray, seed: np.ndarray,
                centre: np.ndarray, size: int, k: int, random_state: int = 0,
                max_descriptors: int = 20000) -> FilterBank:
    """`k` representative patches of all views together (k-means on at most `max_descriptors`
    randomly drawn non-blank patch descriptors; each centre replaced by its nearest real patch).
    `bank.view` is the view the patch was cut from (for back-projection), not a restriction."""
    from .features import patch_descriptors

    n_shapes, n_views = view_maps.shape[:2]
    shape = np.asarray(shape, np.int64)
    view = np.asarray(view, np.int64)
    flat = view_maps.reshape(n_shapes * n_views, *view_maps.shape[2:])
    desc, _ = patch_descriptors(flat, shape * n_views + view, centre, size)
    ok = np.flatnonzero(desc.reshape(len(desc), -1).max(axis=1) > EPS) if len(desc) else \
        np.zeros(0, np.int64)
    if len(ok) > max_descriptors:
        ok = np.sort(np.random.default_rng(random_state).choice(ok, max_descriptors, replace=False))
    pick = ok[representatives(desc[ok], k, random_state)] if len(ok) else ok
    hogs = unit_rows(desc[pick]).reshape(desc[pick].shape) if len(pick) else desc[:0]
    return FilterBank(hogs.astype(np.float32), view[pick], shape[pick],
                      np.asarray(seed, np.int64)[pick], np.asarray(centre, np.float32)[pick])


def word_assignments(maps: np.ndarray, filters: np.ndarray, ink: float = 0.5):
    """One shape's windows against the dictionary: best word, its cosine, and which are inked.

    maps: (V, by, bx, C) the shape's view maps; filters: (K, nb, nb, C). Returns three
    (V, oy, ox) arrays. A window counts as inked when its norm is above `ink` times the median
    norm of the shape's non-empty windows (windows that only clip a line's end or hold stray
    gradient would otherwise be assigned too). Used for the encoding (word counts) and for
    finding where on a drawing the style words are (localisation).
    """
    maps = np.asarray(maps, np.float32)
    v, by, bx, c = maps.shape
    k, nb = len(filters), filters.shape[1]
    oy, ox = by - nb + 1, bx - nb + 1
    if k == 0 or oy <= 0 or ox <= 0:
        z = np.zeros((v, max(oy, 0), max(ox, 0)))
        return z.astype(np.int64), z, z.astype(bool)
    fmat = unit_rows(np.asarray(filters, np.float32).transpose(0, 3, 1, 2)).T
    cols = sliding_window_view(maps, (nb, nb), axis=(1, 2)).reshape(-1, c * nb * nb)
    norm = np.sqrt(np.einsum("ij,ij->i", cols, cols))
    scores = cols @ fmat
    best = scores.argmax(axis=1)
    sim = scores[np.arange(len(best)), best] / np.maximum(norm, EPS)
    nz = norm[norm > EPS]
    inked = norm > ink * np.median(nz) if len(nz) else np.zeros(len(norm), bool)
    shape = (v, oy, ox)
    return best.reshape(shape), sim.reshape(shape), inked.reshape(shape)


def word_counts(view_maps: np.ndarray, filters: np.ndarray, ink: float = 0.5) -> np.ndarray:
    """(N, V, K) number of inked windows of each view whose most similar filter (cosine) is k.

    view_maps: (N, V, by, bx, C); filters: (K, nb, nb, C); see `word_assignments`.
    """
    view_maps = np.asarray(view_maps, np.float32)
    n, v = view_maps.shape[:2]
    k = len(filters)
    out = np.zeros((n, v, k), np.float32)
    for i in range(n):
        best, _, inked = word_assignments(view_maps[i], filters, ink)
        for vv in range(v):
            out[i, vv] = np.bincount(best[vv][inked[vv]], minlength=k)
    return out


def frequency_features(counts: np.ndarray) -> np.ndarray:
    """Square root of the L1-normalised counts over all views of a shape: (N, K).

    Pooling over views makes the feature independent of the (unknown) azimuth; the square root
    (Hellinger map) keeps frequent generic words (straight edges) from swamping rare ornament."""
    h = np.asarray(counts, np.float64).sum(axis=1)
    return np.sqrt(h / np.maximum(h.sum(axis=1, keepdims=True), EPS))
