"""Words and the word encoding of the default method (paper 4.1 end, 4.2).

Words: HOG descriptors of line patterns (`vocabulary`: drawn from synthetic line drawings, the
same whatever the collection). `representatives` is the k-means that picks them (and the
paper's method's per-view filters, paper_method.py); each centre is replaced by the real patch
nearest to it. A `FilterBank` holds the words and, for showing and back-projecting one, where in
the collection it is seen best (shape, view, pixel).

Response = cosine similarity between a filter and a window of a view's HOG map (both as vectors
of block histograms). Why cosine rather than a raw dot product: the HOG blocks are already
L2-normalised, so a raw dot product grows with the number of non-empty blocks in the window,
and a dense tangle of lines would answer every filter. Dividing by both norms leaves only the
agreement of orientation patterns.

Why one dictionary for all views and frequency pooling rather than the paper's per-view filters
with max pooling over the image and its quadrants, measured on the 120-shape sample (Freestyle,
30 seeds; k-means k=4 purity unless said otherwise):
* Shared dictionary: the shapes are upright but not azimuth-aligned, so view v of two shapes
  shows different sides; a per-view dictionary splits one ornament into 12 unrelated filters.
* Frequency ("bag of patches") pooling: the count of inked windows whose best filter is f.
  Max pooling saturates (every drawing has some window that half-matches every filter): with
  true-category centring (an oracle, to measure what the encoding holds) max pooling gave 0.45
  style purity, frequency pooling 0.46 at 48 px and 0.89 at 24 px.
* Quadrant pooling dropped: it encodes where lines are, i.e. layout, i.e. category.
* Small patches (24 px = 3x3 cells = 2x2 blocks): ornaments are small at 200 px; 48 px windows
  are dominated by the part layout around them (see the purities above). 48 px words are kept
  as the layout profile that finds a shape's structural look-alikes (views.py).
* More than one small size: the dictionaries are cut at 24, 16, 32, 24 and 16 px in turn
  (`params.dictionary_patch_size`). One dictionary alone (seed 0, k given), 32 px raised the
  real hu2017 pairs (hu2017-styles-2-0 0.73 -> 0.82, -2-3 0.53 -> 0.62) and lowered generated
  collections (sample-24 0.79 -> 0.54, collection2 0.68 -> 0.57); 16 px raised sample-60
  0.67 -> 0.87 and lowered collection2-styles-2 0.58 -> 0.52. No one size holds everywhere,
  so the style graph fuses them, as it fuses the look-alike ladder's rungs
  (docs/generalisation.md: the five sizes against five 24 px dictionaries).
* Words not drawn from the collection (`vocabulary`): a dictionary of the collection's own
  patches moved with every shape's drawings and seeds, and a few pixels redrawn after a 1e-7
  change of coordinates changed words and with them every shape's profile (sample-24 from OBJ,
  k given: ARI 0.39; docs/generalisation.md).
Vectorised as im2col: the windows of a batch of maps are gathered with a strided view and
multiplied by the (unit) filter matrix in one product; no Python loop over positions.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from sklearn.cluster import KMeans
from threadpoolctl import threadpool_limits


EPS = 1e-6


@dataclass
class FilterBank:
    """Words used as filters and where each is shown; row f of every array describes word f.
    The paper's filters are patches of the collection (shape, seed, view, pixel where cut); the
    default's words are synthetic and shown by the collection's window most like them (seed
    -1; -1 everywhere for words not shown)."""

    hog: np.ndarray       # (F, nb, nb, C) float32, unit L2 norm
    view: np.ndarray      # (F,) int view of the source window (the paper: also where applied)
    shape: np.ndarray     # (F,) int source shape index
    seed: np.ndarray      # (F,) int source seed index (-1: not cut at a seed)
    pixel: np.ndarray     # (F, 2) float32 (x, y) centre of the source window

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
    """Indices of up to `k` real patches, one per k-means centre, nearest to their centre: the
    paper method's representatives of each view's patches.

    Clustering runs on unit-normalised descriptors, matching the cosine used in encoding;
    k-means++ and Lloyd to convergence (scikit-learn, one run). Fewer than `k` are returned
    when there are fewer distinct descriptors. The k-means runs on one thread: scikit-learn's
    Lloyd steps sum each thread's share of the rows and then the shares, so the float32 centres
    round with the number of threads and near-equal patches trade places (the default's
    synthetic words, which used it, came out otherwise on 1 or 2 of seeds 1-3's 10 dictionaries
    with two threads). The BLAS kernels still round them (the default's words now come from
    `vocabulary.exact_kmeans`).
    """
    x = unit_rows(descriptors)
    n = len(x)
    if n == 0 or k <= 0:
        return np.zeros(0, np.int64)
    k = distinct_rows(x, k)
    if k == n:
        return np.arange(n)
    km = KMeans(n_clusters=k, n_init=1, random_state=random_state)
    with threadpool_limits(limits=1):
        labels = km.fit_predict(x)
    d2 = ((x - km.cluster_centers_[labels]) ** 2).sum(axis=1)
    chosen = []
    for c in range(k):
        members = np.flatnonzero(labels == c)
        if len(members):
            chosen.append(members[np.argmin(d2[members])])
    return np.sort(np.asarray(chosen, np.int64))


def distinct_rows(x: np.ndarray, limit: int) -> int:
    """min(`limit`, number of distinct rows of `x` at 5 decimals), from the fewest leading rows
    that settle it (twice `limit`, doubled while too few are distinct): a draw of 20,000
    descriptors has 200 distinct ones among its first 400, and sorting all 20,000 took a tenth
    of the dictionaries' time at 1,050 shapes."""
    m = min(len(x), 2 * limit)
    while True:
        found = len(np.unique(x[:m].round(5), axis=0))
        if found >= limit or m == len(x):
            return min(found, limit)
        m = min(len(x), 2 * m)


def _windows(maps: np.ndarray, nb: int, ink: float):
    """One shape's windows of nb x nb blocks as rows (W, nb*nb*C), their norms, which are inked
    (see `word_assignments`), and the (V, oy, ox) shape they come from; None when the maps are
    smaller than a window."""
    maps = np.asarray(maps, np.float32)
    v, by, bx, c = maps.shape
    oy, ox = by - nb + 1, bx - nb + 1
    if oy <= 0 or ox <= 0:
        return None
    cols = sliding_window_view(maps, (nb, nb), axis=(1, 2)).reshape(-1, c * nb * nb)
    norm = np.sqrt(np.einsum("ij,ij->i", cols, cols))
    nz = norm[norm > EPS]
    inked = norm > ink * np.median(nz) if len(nz) else np.zeros(len(norm), bool)
    return cols, norm, inked, (v, oy, ox)


def _match_scores(rows: np.ndarray, filter_matrix: np.ndarray) -> np.ndarray:
    """Windows' dot products with the unit filters, in float64 and rounded to 1e-9, so that which
    word wins does not depend on the machine. In float32 the products rounded differently with
    the matrix's width and the BLAS threads (an AMD EPYC: the first dictionary's counts changed
    when other dictionaries were matched with it, and a match's cosine with the number of
    jobs), and near-equal words traded places; float64 sums of float32 products differ by about
    1e-16, far below the rounding, and words that tie after it go to the lowest index."""
    return np.round(np.asarray(rows, np.float64) @ np.asarray(filter_matrix, np.float64), 9)


def _filter_matrix(filters: np.ndarray) -> np.ndarray:
    """(nb*nb*C, K) unit filters laid out as the window rows of `_windows`."""
    return unit_rows(np.asarray(filters, np.float32).transpose(0, 3, 1, 2)).T


def word_assignments(maps: np.ndarray, filters: np.ndarray, ink: float = 0.5):
    """One shape's windows against the dictionary: which are inked, and each inked window's
    best word and its cosine (0 for the others, which are never matched).

    maps: (V, by, bx, C) the shape's view maps; filters: (K, nb, nb, C). Returns three
    (V, oy, ox) arrays (best, cosine, inked). A window counts as inked when its norm is above
    `ink` times the median norm of the shape's non-empty windows (windows that only clip a
    line's end or hold stray gradient would otherwise be assigned too). Used for the encoding
    (word counts) and for finding where on a drawing the style words are (localisation).
    """
    v, by, bx, _ = np.shape(maps)
    k, nb = len(filters), filters.shape[1]
    win = _windows(maps, nb, ink) if k else None
    if win is None:
        z = np.zeros((v, max(by - nb + 1, 0), max(bx - nb + 1, 0)))
        return z.astype(np.int64), z, z.astype(bool)
    cols, norm, inked, shape = win
    best = np.zeros(len(cols), np.int64)
    sim = np.zeros(len(cols))
    scores = _match_scores(cols[inked], _filter_matrix(filters))
    best[inked] = scores.argmax(axis=1)
    sim[inked] = scores[np.arange(len(scores)), best[inked]] / np.maximum(norm[inked], EPS)
    return best.reshape(shape), sim.reshape(shape), inked.reshape(shape)


def shape_word_counts(maps: np.ndarray, banks: list, ink: float = 0.5, best: bool = False):
    """One shape's (V, K) word counts against each of several dictionaries of one patch size
    (`word_counts`), its windows cut once and matched against all of them in one matrix
    product (a quarter faster than one per dictionary; each score is the same dot product).
    Only the inked windows are matched (about half of a line drawing's 24 px windows).
    With `best`, also per dictionary the window most like each word: (cosine (K,), view (K,),
    block row (K,), block column (K,)), cosine -1 where no window is inked."""
    maps = np.asarray(maps, np.float32)
    v = maps.shape[0]
    out = [np.zeros((v, len(filters)), np.float32) for filters in banks]
    near = [(np.full(len(f), -1.0), *(np.zeros(len(f), np.int64) for _ in range(3)))
            for f in banks]
    win = _windows(maps, banks[0].shape[1], ink) if banks else None
    if win is None or not any(len(filters) for filters in banks):
        return (out, near) if best else out
    cols, norm, inked, (_, oy, ox) = win
    view = np.repeat(np.arange(v), len(inked) // v)[inked]
    scores = _match_scores(cols[inked],
                           np.concatenate([_filter_matrix(f) for f in banks if len(f)], axis=1))
    filled = [j for j, counts in enumerate(out) if counts.shape[1]]
    ends = np.cumsum([out[j].shape[1] for j in filled])
    where = np.flatnonzero(inked)
    for j, part in zip(filled, np.split(scores, ends[:-1], axis=1)):
        k = part.shape[1]
        out[j][:] = np.bincount(view * k + part.argmax(axis=1), minlength=v * k).reshape(v, k)
        if best:
            cos = part / np.maximum(norm[inked], EPS)[:, None]
            at = cos.argmax(axis=0)
            flat = where[at]
            near[j] = (cos[at, np.arange(k)], flat // (oy * ox), flat // ox % oy, flat % ox)
    return (out, near) if best else out


def word_counts(view_maps: np.ndarray, filters: np.ndarray, ink: float = 0.5) -> np.ndarray:
    """(N, V, K) number of inked windows of each view whose most similar filter (cosine) is k.

    view_maps: (N, V, by, bx, C); filters: (K, nb, nb, C); see `word_assignments`.
    """
    view_maps = np.asarray(view_maps, np.float32)
    return np.stack([shape_word_counts(m, [filters], ink)[0] for m in view_maps]) if \
        len(view_maps) else np.zeros((0, view_maps.shape[1], len(filters)), np.float32)


def frequency_features(counts: np.ndarray) -> np.ndarray:
    """Square root of the L1-normalised counts over all views of a shape: (N, K).

    Pooling over views makes the feature independent of the (unknown) azimuth; the square root
    (Hellinger map) keeps frequent generic words (straight edges) from swamping rare ornament."""
    h = np.asarray(counts, np.float64).sum(axis=1)
    return np.sqrt(h / np.maximum(h.sum(axis=1, keepdims=True), EPS))
