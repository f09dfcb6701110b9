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

The drawings: 200 px canvases of 1 px lines, as Freestyle draws (`synthetic_canvas`): straight
segments, box faces in perspective, ellipses and arcs, curves, families of parallel lines
(slats, mouldings) and chains of small arcs (scallops, beads), at random places, sizes and
angles. A dictionary is `k` representatives (k-means; each centre replaced by its nearest drawn
patch) of 20,000 patch descriptors cut at inked pixels, cut from the canvases' HOG maps exactly
as the collection's windows are (`features.patch_descriptors`), so a word and a window are the
same kind of numbers. Each dictionary is a pure function of (patch size, k, seed): computed
once (some seconds) and kept in the user cache (`words`).
"""
from __future__ import annotations

import functools

import numpy as np
from skimage.draw import bezier_curve, ellipse_perimeter, line, polygon_perimeter

from .encoding import representatives, unit_rows
from .features import hog_images, patch_descriptors

CANVAS = 200                  # px, as the drawings
DESCRIPTORS = 20000           # patches a dictionary is drawn from
PATCHES_PER_CANVAS = 60       # inked pixels a canvas offers at most
# Bump when the canvases, the draw or the k-means change what a dictionary holds.
VOCABULARY_VERSION = "vocabulary-1"


def _put(img: np.ndarray, rr, cc) -> None:
    ok = (rr >= 0) & (rr < CANVAS) & (cc >= 0) & (cc < CANVAS)
    img[rr[ok], cc[ok]] = 1.0


def _segment(img: np.ndarray, p, q) -> None:
    rr, cc = line(int(p[1]), int(p[0]), int(q[1]), int(q[0]))
    _put(img, rr, cc)


def synthetic_canvas(rng: np.random.Generator) -> np.ndarray:
    """One (200, 200) float32 drawing of 4-15 line figures (1 = ink)."""
    img = np.zeros((CANVAS, CANVAS), np.float32)
    for _ in range(rng.integers(4, 16)):
        kind = rng.integers(7)
        c = rng.uniform(0, CANVAS, 2)
        if kind == 0:                                   # straight segment
            a = rng.uniform(0, np.pi)
            half = np.array([np.cos(a), np.sin(a)]) * rng.uniform(5, 150) / 2
            _segment(img, c - half, c + half)
        elif kind == 1:                                 # a box face in perspective
            w, h = rng.uniform(5, 80, 2)
            sk = rng.uniform(-0.5, 0.5, 2)
            pts = c + np.array([[0, 0], [w, w * sk[0]], [w + h * sk[1], w * sk[0] + h],
                                [h * sk[1], h]])
            _put(img, *polygon_perimeter(pts[:, 1], pts[:, 0]))
        elif kind == 2:                                 # ellipse or circle
            r = rng.uniform(2, 50, 2)
            _put(img, *ellipse_perimeter(int(c[1]), int(c[0]), int(r[1]), int(r[0]),
                                         rng.uniform(0, np.pi)))
        elif kind == 3:                                 # arc: part of an ellipse
            r = rng.uniform(4, 60, 2)
            t0 = rng.uniform(0, 2 * np.pi)
            t1 = t0 + rng.uniform(0.5, 3.5, 1)[0]
            ts = np.linspace(t0, t1, 60)
            pts = c + np.stack([r[0] * np.cos(ts), r[1] * np.sin(ts)], 1)
            for p, q in zip(pts[:-1], pts[1:]):
                _segment(img, p, q)
        elif kind == 4:                                 # quadratic curve
            p = rng.uniform(0, CANVAS, (3, 2))
            _put(img, *bezier_curve(int(p[0, 1]), int(p[0, 0]), int(p[1, 1]), int(p[1, 0]),
                                    int(p[2, 1]), int(p[2, 0]), rng.uniform(0.5, 3)))
        elif kind == 5:                                 # parallel family: slats, mouldings
            a = rng.uniform(0, np.pi)
            length = rng.uniform(10, 120)
            n = rng.integers(2, 10)
            gap = rng.uniform(2, 15)
            d = np.array([np.cos(a), np.sin(a)])
            across = np.array([-d[1], d[0]])
            for i in range(n):
                o = c + across * gap * i
                _segment(img, o - d * length / 2, o + d * length / 2)
        else:                                           # chain of small arcs: scallops, beads
            a = rng.uniform(0, np.pi)
            n = rng.integers(3, 10)
            r = rng.uniform(2, 10)
            d = np.array([np.cos(a), np.sin(a)])
            up = rng.choice([-1, 1])
            for i in range(n):
                centre = c + d * 2 * r * i
                ts = np.linspace(a, a + np.pi, 20) if up > 0 else \
                    np.linspace(a + np.pi, a + 2 * np.pi, 20)
                pts = centre + r * np.stack([np.cos(ts), np.sin(ts)], 1)
                for p, q in zip(pts[:-1], pts[1:]):
                    _segment(img, p, q)
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
    """(k, nb, nb, 36) unit words: k-means representatives of `synthetic_descriptors`."""
    desc = synthetic_descriptors(size, seed & 0xFFFFFFFF)
    pick = representatives(desc, k, seed & 0x7FFFFFFF)
    return unit_rows(desc[pick]).reshape(desc[pick].shape).astype(np.float32)


@functools.lru_cache(maxsize=64)
def words(size: int, k: int, seed: int, cache_dir=None) -> np.ndarray:
    """`compute_words`, kept in this process and on disk (`cache.VocabularyCache` under
    `cache_dir`: None the user cache, False none)."""
    from .cache import VocabularyCache
    store = VocabularyCache(cache_dir) if cache_dir is not False else None
    key = VocabularyCache.key(VOCABULARY_VERSION, size, k, seed)
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
