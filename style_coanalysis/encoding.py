"""Representative patches and the word encoding of the default method (paper 4.1 end, 4.2).

Representatives: k-means over the HOG descriptors of patches at visible seeds; each centre is
replaced by the real patch nearest to it, so that every filter ("word") is a patch one can show
and back-project (it remembers shape, view, seed and pixel). The paper's per-view filters and
their max-pooled convolution live with the paper's method (paper_method.py).

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
* The dictionary is drawn by place (shape name, seed, view from the seed's side: `patch_keys`),
  with k-means started by place too (`plusplus_by_key`): mini-batch k-means and a positional
  random draw made one patch more or less change the whole dictionary, a draw by content did
  too, since Freestyle redraws some lines by a pixel when the coordinates change by 1e-7 (98 of
  sample-120's shapes), and so did k-means++'s usual start and Lloyd's steps run to convergence
  (`LLOYD_STEPS`). With all three by place, a few Lloyd steps, and five such dictionaries drawn
  with other seeds in one style graph (pipeline.encode), the file order no longer matters (ARI
  1.00) and x 1.0000001, OBJ and .blend keep ARI 0.82-1.00 (sample-120, collection2, hu2017-all;
  docs/generalisation.md).
Vectorised as im2col: the windows of a batch of maps are gathered with a strided view and
multiplied by the (unit) filter matrix in one product; no Python loop over positions.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from sklearn.cluster import KMeans

from .features import CHANNELS, patch_blocks, patch_descriptors
from .hashing import name_id, uniform

EPS = 1e-6
# Lloyd steps of the default method's dictionaries after their by-place start. Run to
# convergence (about 50 steps), Lloyd carried a change of 3 drawn descriptors of 20,000 (the
# x 1.0000001 drawings of hu2017-all: a few pixels in 13 of 537 shapes) into 540 reassigned
# descriptors and 17 of 200 other words, and the partition with k given to ARI 0.33; after 3
# steps the words are the same and the ARI 0.98 (docs/generalisation.md).
LLOYD_STEPS = 3


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


def representatives(descriptors: np.ndarray, k: int, random_state: int = 0,
                    keys: np.ndarray | None = None) -> np.ndarray:
    """Indices of up to `k` real patches, one per k-means centre, nearest to their centre.

    Clustering runs on unit-normalised descriptors, matching the cosine used in encoding.
    Fewer than `k` are returned when there are fewer distinct descriptors. With `keys` (one
    number per descriptor that depends on the patch's identity, `patch_keys`), k-means starts
    from `plusplus_by_key` and takes `LLOYD_STEPS` steps, so the dictionary follows small
    changes of the descriptors; without, it starts from scikit-learn's k-means++ and runs to
    convergence (the paper's method).
    """
    x = unit_rows(descriptors)
    n = len(x)
    if n == 0 or k <= 0:
        return np.zeros(0, np.int64)
    k = distinct_rows(x, k)
    if k == n:
        return np.arange(n)
    # batch k-means (one run): mini-batches are drawn by position, so one patch more or less
    # would change every batch and the whole dictionary
    if keys is None:
        km = KMeans(n_clusters=k, n_init=1, random_state=random_state)
    else:
        km = KMeans(n_clusters=k, n_init=1, init=x[plusplus_by_key(x, keys, k, random_state)],
                    max_iter=LLOYD_STEPS, random_state=random_state)
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


def plusplus_by_key(x: np.ndarray, keys: np.ndarray, k: int, random_state: int = 0) -> np.ndarray:
    """Indices of greedy k-means++'s `k` starting rows (as scikit-learn's: of 2 + log k rows
    drawn with probability proportional to their squared distance from the rows already
    chosen, the one that lowers the total most), drawn by an exponential race: the rows with
    the largest d^2 / E, E exponential from a hash of (the row's key, the step).

    k-means++ as usually drawn (a uniform number looked up in the running sum of d^2) picks
    the row at a position: when a few rows change a little (a line redrawn by a pixel in two of
    60 shapes), every later position shifts and other rows are drawn; 130 of 200 words of
    hu2017-60-0 changed that way. In the race a row is only displaced by rows near it in d^2/E."""
    base = (np.asarray(keys, np.float64) * float(1 << 53)).astype(np.uint64)
    rs = int(random_state) & 0xFFFFFFFF
    tries = 2 + int(np.log(k))

    def exponential(step):
        return -np.log1p(-uniform(base, step, rs)) + 1e-300

    x = np.asarray(x, np.float64)
    sq = (x * x).sum(axis=1)

    def dist2(rows):                               # (N, len(rows)) squared distances
        # the few rows times all, then transposed: the same products, twice as fast as x @ x[rows].T
        return np.maximum(sq[:, None] - 2 * (x[rows] @ x.T).T + sq[rows][None], 0.0)

    chosen = [int(np.argmin(exponential(0)))]
    d2 = dist2([chosen[0]])[:, 0]
    for step in range(1, k):
        race = d2 / exponential(step)
        cand = np.argpartition(-race, tries)[:tries] if len(x) > tries else np.arange(len(x))
        cand = cand[np.argsort(-race[cand], kind="stable")]
        new = np.minimum(d2[:, None], dist2(cand))
        best = int(np.argmin(new.sum(axis=0)))
        chosen.append(int(cand[best]))
        d2 = new[:, best]
    return np.asarray(chosen, np.int64)


def home_views(seeds: np.ndarray, n_views: int) -> np.ndarray:
    """(S,) the view each surface seed faces: the rig camera whose azimuth is nearest the
    seed's own azimuth about +Z (the rig's cameras are `n_views` evenly spaced azimuths, view 0
    at azimuth 0, `rig.Rig.azimuths`)."""
    seeds = np.asarray(seeds, np.float64).reshape(-1, 3)
    step = 2.0 * np.pi / n_views
    return np.round(np.arctan2(seeds[:, 1], seeds[:, 0]) / step).astype(np.int64) % n_views


def patch_keys(name: str, view: np.ndarray, seed: np.ndarray, salt: int = 0,
               home: np.ndarray | None = None, n_views: int = 12) -> np.ndarray:
    """A pseudo-random number in [0, 1) per patch that depends on where it was cut only: the
    shape's name, the seed, and the view counted from the seed's home view (`home_views`,
    indexed by seed; the view itself without `home`) (`hashing.uniform`).

    Not on its content: a 1e-7 change of coordinates redraws some of Freestyle's lines by a
    pixel, and a key of the descriptor's values then drew other patches and reordered them, so
    every dictionary word changed (issue 11). By place, the same patches are drawn, in the same
    order, whatever order the shapes are read in, and a seed more or less changes one patch.
    Counted from the home view, a shape turned by a multiple of 30 degrees about its up axis
    (the same 12 drawings in another order: a chair facing +X rather than -Y) draws the same
    patches; keyed by the view itself it drew others, and hu2017-60-0 turned by 90 degrees was
    cut otherwise (ARI 0.62 with k given; 1.00 with the home view)."""
    view = np.asarray(view, np.int64)
    if home is not None:
        view = (view - np.asarray(home, np.int64)[np.asarray(seed, np.int64)]) % n_views
    return uniform(name_id(name), view, seed, salt)


class DescriptorDraw:
    """The patch descriptors a dictionary is drawn from, gathered one shape at a time.

    Non-blank descriptors only, at most `limit` of them, drawn by place (the smallest
    `patch_keys`), not by position in the input nor by content: the order of the shapes does
    not matter, a patch more or less changes the draw by that patch only, a patch whose lines
    moved by a pixel stays in the draw, and a collection of any size holds at most 2 x `limit`
    descriptors."""

    def __init__(self, size: int, limit: int = 20000, salt: int = 1):
        self.size, self.limit, self.salt = size, limit, salt
        self._parts: list[tuple] = []
        self._count = 0

    def add(self, maps: np.ndarray, shape: int, name: str, view: np.ndarray, seed: np.ndarray,
            centre: np.ndarray, home: np.ndarray | None = None) -> None:
        """Patches of one shape: its maps (V, by, bx, C), index and name, per patch its view,
        seed and centre, and per seed its home view (`home_views`; None: key by the view)."""
        view = np.asarray(view, np.int64)
        if len(view) == 0:
            return
        desc, _ = patch_descriptors(maps, view, centre, self.size)
        ok = desc.reshape(len(desc), -1).max(axis=1) > EPS
        if not ok.any():
            return
        desc = desc[ok]
        seed = np.asarray(seed, np.int64)[ok]
        self._parts.append((patch_keys(name, view[ok], seed, self.salt, home, len(maps)), desc,
                            np.full(len(desc), shape), view[ok], seed,
                            np.asarray(centre, np.float32)[ok]))
        self._count += len(desc)
        if self._count > 2 * self.limit:
            self._prune()

    def _prune(self) -> None:
        keys, *rest = (np.concatenate(c) for c in zip(*self._parts))
        keep = np.argsort(keys, kind="stable")[:self.limit]
        self._parts = [(keys[keep], *(r[keep] for r in rest))]
        self._count = len(keep)

    def bank(self, k: int, random_state: int = 0) -> FilterBank:
        """`k` representative patches of the drawn descriptors, in the draw's order (k-means;
        each centre replaced by its nearest real patch). `bank.view` is the view the patch was
        cut from (for back-projection), not a restriction."""
        if self._count > self.limit:
            self._prune()
        if not self._parts:
            nb = patch_blocks(self.size)
            return FilterBank(np.zeros((0, nb, nb, CHANNELS), np.float32), np.zeros(0, np.int64),
                              np.zeros(0, np.int64), np.zeros(0, np.int64),
                              np.zeros((0, 2), np.float32))
        keys, desc, shape, view, seed, centre = (np.concatenate(c) for c in zip(*self._parts))
        order = np.argsort(keys, kind="stable")     # k-means reads them in an order by place
        pick = order[representatives(desc[order], k, random_state, keys[order])]
        hogs = unit_rows(desc[pick]).reshape(desc[pick].shape)
        return FilterBank(hogs.astype(np.float32), view[pick], shape[pick], seed[pick],
                          centre[pick])


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


def shape_word_counts(maps: np.ndarray, banks: list, ink: float = 0.5) -> list:
    """One shape's (V, K) word counts against each of several dictionaries of one patch size
    (`word_counts`), its windows cut once and matched against all of them in one matrix
    product (a quarter faster than one per dictionary; each score is the same dot product).
    Only the inked windows are matched (about half of a line drawing's 24 px windows)."""
    maps = np.asarray(maps, np.float32)
    v = maps.shape[0]
    out = [np.zeros((v, len(filters)), np.float32) for filters in banks]
    win = _windows(maps, banks[0].shape[1], ink) if banks else None
    if win is None or not any(len(filters) for filters in banks):
        return out
    cols, _, inked, _ = win
    view = np.repeat(np.arange(v), len(inked) // v)[inked]
    scores = _match_scores(cols[inked],
                           np.concatenate([_filter_matrix(f) for f in banks if len(f)], axis=1))
    filled = [counts for counts in out if counts.shape[1]]
    ends = np.cumsum([counts.shape[1] for counts in filled])
    for counts, part in zip(filled, np.split(scores, ends[:-1], axis=1)):
        k = part.shape[1]
        counts[:] = np.bincount(view * k + part.argmax(axis=1), minlength=v * k).reshape(v, k)
    return out


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
