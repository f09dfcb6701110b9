"""Stand-in hand sketches for testing style identification from 2D drawings (issue 14, item 3).

No labelled sketches of these collections exist, so: line drawings of meshes the 3D set does not
contain, from views its rig does not use (another elevation and azimuth spacing), made thicker,
jittered by a smooth random warp and broken in places, at another size, and written half as
dark-on-light PNG and half as light-on-dark JPEG. A stand-in, not real hand drawing.

Strokes are 3 px at 320 px (about twice the views' lines). A first version drew 5 px strokes
after a lenient resize threshold: the blobs filled in lattices and carvings that a person
sketching the piece would draw, and identify reached 0.42 on sample-120 (seed 0; whole-image
orientation statistics 0.32).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter, map_coordinates
from PIL import Image
from skimage.morphology import dilation, disk
from skimage.transform import resize

from ..params import DrawingSettings

# views the rig (12 azimuths from 0 deg, 30 deg up) never uses
SKETCH_SETTINGS = DrawingSettings(renderer="lineart", n_views=5, elevation_deg=12.0, n_seeds=4)


def sketchify(ink: np.ndarray, rng: np.random.Generator, size: int = 320) -> np.ndarray:
    """(H, W) ink in [0, 1] -> (size, size) ink: thicker, jittered, partly broken strokes."""
    img = resize(np.asarray(ink, np.float64), (size, size), order=1) > 0.5
    img = dilation(img, disk(max(1, size // 320)))                   # thicker strokes
    amp, smooth = size / 100.0, size / 20.0
    dy = gaussian_filter(rng.standard_normal((size, size)), smooth)
    dx = gaussian_filter(rng.standard_normal((size, size)), smooth)
    dy *= amp / max(np.abs(dy).max(), 1e-9)
    dx *= amp / max(np.abs(dx).max(), 1e-9)
    yy, xx = np.mgrid[:size, :size].astype(np.float64)
    img = map_coordinates(img.astype(np.float64), [yy + dy, xx + dx], order=1) > 0.5
    ys, xs = np.nonzero(img)                                         # breaks: gaps in strokes
    if len(ys):
        for k in rng.choice(len(ys), size=min(len(ys), 25), replace=False):
            r = int(rng.integers(2, max(3, size // 60)))
            img[max(0, ys[k] - r):ys[k] + r, max(0, xs[k] - r):xs[k] + r] = False
    return img.astype(np.float32)


def write_sketches(drawings, styles, folder, seed: int = 0) -> list[Path]:
    """Each (V, H, W) view stack of `drawings` (ShapeDrawings-like: .images, .name), its views
    as sketches under folder/<style>/; returns the files written."""
    rng = np.random.default_rng(seed)
    out = []
    for d, style in zip(drawings, styles):
        sub = Path(folder) / str(style)
        sub.mkdir(parents=True, exist_ok=True)
        for v, view in enumerate(np.asarray(d.images)):
            if view.max() <= 0:
                continue
            ink = sketchify(view, rng)
            if len(out) % 2 == 0:
                path = sub / f"{d.name}_{v}.png"
                Image.fromarray(((1 - ink) * 255).astype(np.uint8)).save(path)
            else:
                path = sub / f"{d.name}_{v}.jpg"
                Image.fromarray((ink * 255).astype(np.uint8)).save(path, quality=90)
            out.append(path)
    return out
