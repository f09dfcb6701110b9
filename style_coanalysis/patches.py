"""Mid-level patches (paper 4.1): square windows of the line drawings around visible seeds.

A patch is cut for every (shape, view, seed) where the seed is visible in that view, centred on
the seed's projection, zero-padded where it overhangs the image border. Windows with almost no
ink are dropped: a seed in the middle of a flat face sees only blank paper, whose HOG is zero and
would pull a k-means centre towards "nothing".

Blank threshold (`MIN_INK` = 0.01, as a fraction of the window's area): one 1-pixel line crossing
a 48x48 window covers about 48 pixels = 2 % of it, so 1 % keeps any window holding at least half a
window-length of line and drops windows that only clip a stroke's end or a few stray pixels.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PATCH_SIZE = 48
MIN_INK = 0.01


@dataclass
class Patches:
    """Patches cut from a collection's drawings; row i of every array describes patch i."""

    images: np.ndarray      # (n, size, size) float32, 1 = ink
    shape: np.ndarray       # (n,) int32 index into the drawings list
    view: np.ndarray        # (n,) int32 view index
    seed: np.ndarray        # (n,) int32 seed index within the shape
    centre: np.ndarray      # (n, 2) float32 (x, y) pixel the window is centred on

    def __len__(self) -> int:
        return int(len(self.images))

    def subset(self, mask_or_index) -> "Patches":
        return Patches(self.images[mask_or_index], self.shape[mask_or_index],
                       self.view[mask_or_index], self.seed[mask_or_index],
                       self.centre[mask_or_index])


def window_origins(pixels: np.ndarray, size: int) -> np.ndarray:
    """(n, 2) integer (row, col) of each window's top-left pixel.

    The window holds the pixel containing (x, y) at index size // 2 along both axes, so an even
    size is centred to within half a pixel (the pixel under the point sits just right of/below
    the middle).
    """
    pixels = np.asarray(pixels, np.float64).reshape(-1, 2)
    col = np.floor(pixels[:, 0]).astype(np.int64) - size // 2
    row = np.floor(pixels[:, 1]).astype(np.int64) - size // 2
    return np.stack([row, col], axis=1)


def patches_at(image: np.ndarray, pixels: np.ndarray, size: int = PATCH_SIZE) -> np.ndarray:
    """Windows of `image` (H, W) centred on each (x, y) in `pixels`: (n, size, size) float32.

    Usable for any set of points (e.g. the denser seeds of the back-projection). Parts of a
    window outside the image are zero (paper); points far outside give all-zero windows.
    """
    image = np.asarray(image, np.float32)
    origins = window_origins(pixels, size)
    if len(origins) == 0:
        return np.zeros((0, size, size), np.float32)
    padded = np.pad(image, size)
    # clamp so that points far off the image read blank padding instead of indexing out of bounds
    r0 = np.clip(origins[:, 0] + size, 0, padded.shape[0] - size)
    c0 = np.clip(origins[:, 1] + size, 0, padded.shape[1] - size)
    off = np.arange(size)
    rows = (r0[:, None] + off)[:, :, None]
    cols = (c0[:, None] + off)[:, None, :]
    return padded[rows, cols]


def ink_fraction(windows: np.ndarray) -> np.ndarray:
    """Mean ink per window (the fraction of its area covered by lines)."""
    windows = np.asarray(windows, np.float32)
    return windows.reshape(len(windows), -1).mean(axis=1)


def extract_patches(drawings_list, size: int = PATCH_SIZE, min_ink: float = MIN_INK) -> Patches:
    """Patches around every visible seed of every view of every shape, blank windows dropped.

    `drawings_list` is a sequence of `ShapeDrawings`. Order: shape, then view, then seed.
    """
    parts = []
    for s, d in enumerate(drawings_list):
        for v in range(d.n_views):
            idx = np.flatnonzero(d.seed_visible[v])
            if len(idx) == 0:
                continue
            centres = np.asarray(d.seed_pixels[v, idx], np.float32)
            windows = patches_at(d.images[v], centres, size)
            keep = ink_fraction(windows) >= min_ink
            if not keep.any():
                continue
            k = int(keep.sum())
            parts.append(Patches(windows[keep], np.full(k, s, np.int32), np.full(k, v, np.int32),
                                 idx[keep].astype(np.int32), centres[keep]))
    if not parts:
        return Patches(np.zeros((0, size, size), np.float32), np.zeros(0, np.int32),
                       np.zeros(0, np.int32), np.zeros(0, np.int32), np.zeros((0, 2), np.float32))
    return Patches(*(np.concatenate([getattr(p, f) for p in parts])
                     for f in ("images", "shape", "view", "seed", "centre")))
