"""The default method's words: line patterns drawn from synthetic line drawings, not from the
collection.

Why not the collection's own patches (the paper's representatives, and this method's until
issue 11's stability screens): a dictionary drawn from the collection makes every shape's
encoding depend on every other shape's drawings and surface seeds. A few vertices moved by a
rounding (a mesh read back from OBJ, coordinates x 1.0000001) redraw a few pixels of a few shapes
or move a seed, the k-means over the drawn patches then settles on other words, and every shape's
profile changes with them: on the collections whose cut the data hold only loosely the partition
moved (sample-24 from OBJ, k given: ARI 0.39). Drawn from fixed synthetic drawings, the words are
the same whatever the collection, so a shape's profile depends on its own drawings only, and a
shape drawn a little differently changes its own row.

The drawings: 200 px canvases of 1 px lines, as Freestyle draws (`synthetic_canvas`): the
plain lines of a build (straight segments, box faces in perspective, ellipses and arcs, curves,
families of parallel lines, chains of small arcs) and small ornaments (fans and shells,
spirals, lattices, twisted bands, nested outlines, rows of blocks, turned profiles), at random
places, sizes and angles. Without the ornaments the words lost the generated collections'
carvings (collection2 k given 0.689 -> 0.594; with them 0.672, docs/generalisation.md).

A dictionary is `k` representatives (k-means; each centre replaced by its nearest drawn patch)
of 20,000 patch descriptors cut at inked pixels, cut from the canvases' HOG maps exactly as the
collection's windows are (`features.patch_descriptors`), so a word and a window are the same
kind of numbers. Each dictionary is a function of (patch size, k, seed) alone: the k-means runs
on exact numbers (`exact_kmeans`), so no machine's BLAS kernels or threads draw other words
(scikit-learn's k-means drew other words for 2 of seed 2's 10 dictionaries under OpenBLAS's
Haswell and SkylakeX kernels, and for 2-4 of each seed's under its Prescott ones;
docs/generalisation.md, "The same shapes on other machines"). The default analysis seed's ten
ship with the package (`SHIPPED`, made by `tools/make_vocabularies.py`; the suite checks they
are what `compute_words` makes), so no run computes them; another seed's are computed once
(about a minute for ten) and kept in the cache (`words`).
"""
from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
from scipy import sparse
from skimage.draw import bezier_curve, ellipse_perimeter, line, polygon_perimeter
from sklearn.cluster import kmeans_plusplus

from .encoding import distinct_rows, unit_rows
from .features import hog_images, patch_descriptors

CANVAS = 200                  # px, as the drawings
DESCRIPTORS = 20000           # patches a dictionary is drawn from
PATCHES_PER_CANVAS = 60       # inked pixels a canvas offers at most
SHIPPED = Path(__file__).with_name("vocabularies.npz")    # the default seed's, `shipped_name`
GRID = 2.0 ** -16             # `exact_kmeans`' coordinates


def _put(img: np.ndarray, rr, cc) -> None:
    ok = (rr >= 0) & (rr < CANVAS) & (cc >= 0) & (cc < CANVAS)
    img[rr[ok], cc[ok]] = 1.0


def _segment(img: np.ndarray, p, q) -> None:
    rr, cc = line(int(p[1]), int(p[0]), int(q[1]), int(q[0]))
    _put(img, rr, cc)


def _polyline(img: np.ndarray, pts) -> None:
    for p, q in zip(pts[:-1], pts[1:]):
        _segment(img, p, q)


def _arc(img: np.ndarray, c, rx, ry, t0, t1, n: int = 24) -> None:
    ts = np.linspace(t0, t1, n)
    _polyline(img, c + np.stack([rx * np.cos(ts), ry * np.sin(ts)], 1))


def _figure(img: np.ndarray, rng: np.random.Generator, kind: int) -> None:
    """One line figure: the first seven the plain lines of a build, the rest small ornaments."""
    c = rng.uniform(0, CANVAS, 2)
    a = rng.uniform(0, np.pi)
    d = np.array([np.cos(a), np.sin(a)])
    across = np.array([-d[1], d[0]])
    if kind == 0:                                       # straight segment
        half = d * rng.uniform(5, 150) / 2
        _segment(img, c - half, c + half)
    elif kind == 1:                                     # a box face in perspective
        w, h = rng.uniform(5, 80, 2)
        sk = rng.uniform(-0.5, 0.5, 2)
        pts = c + np.array([[0, 0], [w, w * sk[0]], [w + h * sk[1], w * sk[0] + h],
                            [h * sk[1], h]])
        _put(img, *polygon_perimeter(pts[:, 1], pts[:, 0]))
    elif kind == 2:                                     # ellipse or circle
        r = rng.uniform(2, 50, 2)
        _put(img, *ellipse_perimeter(int(c[1]), int(c[0]), int(r[1]), int(r[0]),
                                     rng.uniform(0, np.pi)))
    elif kind == 3:                                     # arc: part of an ellipse
        r = rng.uniform(4, 60, 2)
        t0 = rng.uniform(0, 2 * np.pi)
        _arc(img, c, r[0], r[1], t0, t0 + rng.uniform(0.5, 3.5), 60)
    elif kind == 4:                                     # quadratic curve
        p = rng.uniform(0, CANVAS, (3, 2))
        _put(img, *bezier_curve(int(p[0, 1]), int(p[0, 0]), int(p[1, 1]), int(p[1, 0]),
                                int(p[2, 1]), int(p[2, 0]), rng.uniform(0.5, 3)))
    elif kind == 5:                                     # parallel family: slats, mouldings
        length, gap = rng.uniform(10, 120), rng.uniform(2, 15)
        for i in range(rng.integers(2, 10)):
            o = c + across * gap * i
            _segment(img, o - d * length / 2, o + d * length / 2)
    elif kind == 6:                                     # chain of small arcs: scallops, beads
        r = rng.uniform(2, 10)
        flip = rng.choice([0.0, np.pi])
        for i in range(rng.integers(3, 10)):
            _arc(img, c + d * 2 * r * i, r, r, a + flip, a + flip + np.pi, 20)
    elif kind == 7:                                     # fan or shell: rays under an arc
        r = rng.uniform(6, 30)
        span = rng.uniform(np.pi / 2, 2 * np.pi)
        n = rng.integers(5, 16)
        for t in a + np.linspace(0, span, n):
            _segment(img, c + r * 0.15 * np.array([np.cos(t), np.sin(t)]),
                     c + r * np.array([np.cos(t), np.sin(t)]))
        _arc(img, c, r, r, a, a + span, 40)
    elif kind == 8:                                     # spiral: a volute, a carved scroll
        turns = rng.uniform(1.5, 4)
        ts = np.linspace(0, 2 * np.pi * turns, int(40 * turns))
        rr = rng.uniform(2, 5) * ts / (2 * np.pi)
        _polyline(img, c + np.stack([rr * np.cos(ts + a), rr * np.sin(ts + a)], 1))
    elif kind == 9:                                     # lattice: fretwork, caning, a grille
        size, gap = rng.uniform(10, 50), rng.uniform(3, 10)
        b = a + rng.choice([np.pi / 2, np.pi / 3, np.pi / 4])
        e = np.array([np.cos(b), np.sin(b)])
        for s in np.arange(-size / 2, size / 2, gap):
            _segment(img, c + across * s - d * size / 2, c + across * s + d * size / 2)
            f = np.array([-e[1], e[0]])
            _segment(img, c + f * s - e * size / 2, c + f * s + e * size / 2)
    elif kind == 10:                                    # twist: a band of slanted curves
        length, width = rng.uniform(20, 120), rng.uniform(4, 14)
        gap, slant = rng.uniform(3, 10), rng.uniform(0.4, 1.5)
        for o in (-width / 2, width / 2):
            _segment(img, c + across * o - d * length / 2, c + across * o + d * length / 2)
        for s in np.arange(-length / 2, length / 2, gap):
            ts = np.linspace(-1, 1, 8)
            pts = c + np.outer(s + slant * width / 2 * ts + 0.2 * width * (1 - ts ** 2), d) \
                + np.outer(ts * width / 2, across)
            _polyline(img, pts)
    elif kind == 11:                                    # nested outlines: a panel, a moulding
        w, h = rng.uniform(10, 70, 2)
        inset = rng.uniform(2, 6)
        for i in range(rng.integers(2, 5)):
            m = inset * i
            if w - 2 * m < 2 or h - 2 * m < 2:
                break
            pts = c + np.outer([m, w - m, w - m, m], d) + np.outer([m, m, h - m, h - m], across)
            _put(img, *polygon_perimeter(pts[:, 1], pts[:, 0]))
    elif kind == 12:                                    # a row of small blocks: dentils, teeth
        w, h = rng.uniform(2, 8), rng.uniform(3, 12)
        for i in range(rng.integers(4, 14)):
            o = c + d * 2 * w * i
            pts = o + np.outer([0, w, w, 0], d) + np.outer([0, 0, h, h], across)
            _put(img, *polygon_perimeter(pts[:, 1], pts[:, 0]))
    else:                                               # a turned profile: bulbs and necks
        length = rng.uniform(20, 120)
        waves, amp = rng.integers(1, 4), rng.uniform(2, 8)
        ts = np.linspace(0, 1, 60)
        radius = amp * (1.2 + np.sin(2 * np.pi * waves * ts + rng.uniform(0, np.pi)))
        for side in (-1, 1):
            _polyline(img, c + np.outer((ts - 0.5) * length, d) + np.outer(side * radius, across))


N_FIGURES = 14


def synthetic_canvas(rng: np.random.Generator) -> np.ndarray:
    """One (200, 200) float32 drawing of 4-15 line figures (1 = ink)."""
    img = np.zeros((CANVAS, CANVAS), np.float32)
    for _ in range(rng.integers(4, 16)):
        _figure(img, rng, int(rng.integers(N_FIGURES)))
    return img


def synthetic_descriptors(size: int, seed: int, n: int = DESCRIPTORS) -> np.ndarray:
    """(n, nb, nb, 36) HOG descriptors of `size` px patches centred on inked pixels of
    synthetic canvases (12 at a time, as a shape's views), blank ones left out."""
    rng = np.random.default_rng(seed)
    out, total = [], 0
    while total < n:
        images = np.stack([synthetic_canvas(rng) for _ in range(12)])
        maps = hog_images(images)
        for v in range(len(images)):
            ys, xs = np.nonzero(images[v])
            if len(ys) == 0:
                continue
            pick = rng.choice(len(ys), min(PATCHES_PER_CANVAS, len(ys)), replace=False)
            centres = np.stack([xs[pick], ys[pick]], 1).astype(np.float32)
            desc, _ = patch_descriptors(maps, np.full(len(pick), v), centres, size)
            desc = desc[desc.reshape(len(desc), -1).max(axis=1) > 1e-6]
            out.append(desc)
            total += len(desc)
    return np.concatenate(out)[:n]


def compute_words(size: int, k: int, seed: int) -> np.ndarray:
    """(k, nb, nb, 36) unit words: the descriptors of `synthetic_descriptors` nearest to the
    centres of `exact_kmeans`, so the same bits on every machine and any number of threads."""
    desc = synthetic_descriptors(size, seed & 0xFFFFFFFF)
    x = unit_rows(desc)
    labels, centres = exact_kmeans(x, distinct_rows(x, k), seed & 0x7FFFFFFF)
    xg = _on_grid(x)
    d2 = ((xg - centres[labels]) ** 2).sum(axis=1)
    pick = [members[np.argmin(d2[members])]
            for members in (np.flatnonzero(labels == c) for c in range(len(centres)))
            if len(members)]
    pick = np.sort(np.asarray(pick, np.int64))
    return unit_rows(desc[pick]).reshape(desc[pick].shape).astype(np.float32)


def _on_grid(x: np.ndarray) -> np.ndarray:
    """`x` in float64 rounded to multiples of `GRID`."""
    return np.round(np.asarray(x, np.float64) / GRID) * GRID


def exact_kmeans(x: np.ndarray, k: int, random_state: int, max_iter: int = 300):
    """(labels, centres) of k-means on the unit rows `x`, whose every number is exact.

    Why not scikit-learn's: its float distances round with the BLAS kernels, and where two
    distances are equal or nearly so the kernels break the tie otherwise, so another machine
    drew other words from the same seed (docs/generalisation.md, "The same shapes on other
    machines"). Here the rows and centres lie on a grid of 2^-16, so every product is a
    multiple of 2^-32 and every sum this runs (a dot product of unit rows, a centre's sum of
    at most 20,000 rows, k-means++'s potentials, at most 80,000) stays below 2^53 of them: exact
    in float64 whatever the summation order, hence whatever the kernels and threads. k-means++
    starts it (scikit-learn's, on those exact distances); Lloyd steps, each centre the mean of
    its rows rounded to the grid (an emptied centre stays), run until the partition repeats;
    equal distances go to the lower centre."""
    xg = _on_grid(x)
    centres, _ = kmeans_plusplus(xg, k, random_state=random_state)
    centres = _on_grid(centres)
    labels = None
    for _ in range(max_iter):
        d = (centres * centres).sum(axis=1)[None, :] - 2.0 * (xg @ centres.T)
        new = d.argmin(axis=1)
        if labels is not None and np.array_equal(new, labels):
            break
        labels = new
        counts = np.bincount(labels, minlength=k)
        members = sparse.csr_matrix((np.ones(len(xg)), (labels, np.arange(len(xg)))),
                                    shape=(k, len(xg)))
        sums = members @ xg
        filled = counts > 0
        centres[filled] = _on_grid(sums[filled] / counts[filled, None])
    return labels, centres


def shipped_name(size: int, k: int, seed: int) -> str:
    """The array name of a dictionary in `SHIPPED`."""
    return f"{size}_{k}_{seed}"


@functools.lru_cache(maxsize=1)
def _shipped() -> dict:
    with np.load(SHIPPED) as z:
        arrays = {name: z[name] for name in z.files}
    for a in arrays.values():
        a.flags.writeable = False          # shared by every analysis of the process
    return arrays


@functools.lru_cache(maxsize=64)
def words(size: int, k: int, seed: int, cache_dir=None) -> np.ndarray:
    """`compute_words`: the package's `SHIPPED` copy when it has one, else kept in this process
    and on disk (`cache.VocabularyCache` under `cache_dir`: None the user cache, False none)."""
    shipped = _shipped().get(shipped_name(size, k, seed))
    if shipped is not None:
        return shipped
    from .cache import VocabularyCache
    store = VocabularyCache(cache_dir) if cache_dir is not False else None
    key = VocabularyCache.key(size, k, seed)
    found = store.load(key) if store is not None else None
    if found is not None:
        return found
    made = compute_words(size, k, seed)
    if store is not None:
        try:
            store.store(key, made)
        except OSError:      # a read-only cache costs a recomputation, never the analysis
            pass
    return made
