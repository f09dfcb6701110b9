"""Procedural line drawings with a known style and a distracting category, for pipeline tests.

Each shape has a style (the motif stamped on its ornament seeds: rings, plus-crosses or diagonal zigzags) and a
category (the outline: a wide, a tall or a square box), drawn in several views whose outline
aspect changes with the view angle, as a rotating object's would. The category is a distractor:
long outline lines in every patch near the border, while the style lives only in small
repeated motifs whose number varies per shape (as ornament does on real furniture), plus a
few style-free stray strokes.
"""
from __future__ import annotations

import numpy as np

from style_coanalysis.drawings import ShapeDrawings

STYLES = ("rings", "crosses", "zigzags")
CATEGORIES = ("wide", "tall", "square")


def motif(style: str, size: int, rng) -> np.ndarray:
    m = np.zeros((size, size), np.float32)
    yy, xx = np.mgrid[:size, :size] - (size - 1) / 2
    if style == "rings":
        m[np.abs(np.hypot(yy, xx) - size * rng.uniform(0.28, 0.4)) < 0.9] = 1
    elif style == "crosses":
        m[np.abs(yy) < 0.9] = 1
        m[np.abs(xx) < 0.9] = 1
    else:
        period = size / rng.uniform(1.5, 2.5)              # a few bold diagonal teeth
        wave = (np.abs(((xx / period) % 1.0) - 0.5) - 0.25) * period * 2.0
        m[np.abs(yy - wave) < 1.0] = 1
    return m


def _stamp(img, m, x, y):
    s = m.shape[0]
    r0, c0 = int(y) - s // 2, int(x) - s // 2
    rs, cs = slice(max(r0, 0), min(r0 + s, img.shape[0])), slice(max(c0, 0), min(c0 + s, img.shape[1]))
    img[rs, cs] = np.maximum(img[rs, cs], m[rs.start - r0:rs.stop - r0, cs.start - c0:cs.stop - c0])


def _line(img, x0, y0, x1, y1):
    n = int(max(abs(x1 - x0), abs(y1 - y0))) + 1
    xs = np.clip(np.rint(np.linspace(x0, x1, n)).astype(int), 0, img.shape[1] - 1)
    ys = np.clip(np.rint(np.linspace(y0, y1, n)).astype(int), 0, img.shape[0] - 1)
    img[ys, xs] = 1


def make_shape(name: str, style: int, category: int, rng, n_views: int = 6, size: int = 200,
               n_seeds: int = 30) -> ShapeDrawings:
    images = np.zeros((n_views, size, size), np.float32)
    aspect = {0: (1.5, 0.8), 1: (0.75, 1.5), 2: (1.1, 1.1)}[category]   # the outline's shape
    aspect = (aspect[0] * rng.uniform(0.9, 1.1), aspect[1] * rng.uniform(0.9, 1.1))
    density = rng.uniform(0.35, 0.85)                          # how ornate this shape is
    # seeds in the box's own (u, w) coordinates: a third on the outline, the rest ornament
    n_edge = n_seeds // 3
    uw = rng.uniform(0.12, 0.88, (n_seeds, 2))
    side = rng.integers(0, 4, n_edge)
    uw[np.arange(n_edge), side % 2] = np.where(side < 2, 0.0, 1.0)
    visible = rng.random((n_views, n_seeds)) < 0.8
    pixels = np.zeros((n_views, n_seeds, 2), np.float32)
    for v in range(n_views):
        img = images[v]
        turn = 0.75 + 0.25 * np.cos(2 * np.pi * v / n_views)
        w, h = 55 * aspect[0] * turn, 55 * aspect[1]
        cx, cy = size / 2 + rng.uniform(-5, 5), size / 2 + rng.uniform(-5, 5)
        x0, x1, y0, y1 = cx - w, cx + w, cy - h, cy + h
        for a, b, c, d in [(x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0)]:
            _line(img, a, b, c, d)
        pixels[v] = np.stack([x0 + uw[:, 0] * (x1 - x0), y0 + uw[:, 1] * (y1 - y0)], axis=1)
        for j in range(n_edge, n_seeds):
            if visible[v, j] and rng.random() < density:
                _stamp(img, motif(STYLES[style], int(rng.integers(18, 27)), rng), *pixels[v, j])
        for _ in range(3):                   # distractor strokes, style-free
            a = rng.uniform(20, size - 20, 2)
            _line(img, *a, *(a + rng.uniform(-25, 25, 2)))
    return ShapeDrawings(
        name=name, images=images, cameras=np.zeros((n_views, 3, 4)),
        seeds=rng.standard_normal((n_seeds, 3)).astype(np.float32),
        seed_faces=np.zeros(n_seeds, np.int32), seed_visible=visible, seed_pixels=pixels)


def make_collection(n_per_cell: int = 4, n_views: int = 6, seed: int = 0):
    """(drawings, style ids, category ids): every style crossed with every category."""
    rng = np.random.default_rng(seed)
    drawings, styles, cats = [], [], []
    for s in range(len(STYLES)):
        for c in range(len(CATEGORIES)):
            for k in range(n_per_cell):
                drawings.append(make_shape(f"{CATEGORIES[c]}_{STYLES[s]}_{k}", s, c, rng, n_views))
                styles.append(s)
                cats.append(c)
    order = rng.permutation(len(drawings))          # no meaning in the order
    return ([drawings[i] for i in order], np.array(styles)[order], np.array(cats)[order])


def purity(pred, truth) -> float:
    """Paper eq. 5: share of shapes that belong to their cluster's majority class."""
    pred, truth = np.asarray(pred), np.asarray(truth)
    return sum(np.bincount(truth[pred == c]).max() for c in np.unique(pred)) / len(truth)
