"""`python -m style_coanalysis render INPUT --out DIR`: each shape's 12 line drawings as PNG.

Writes DIR/<shape>/view_00.png .. view_11.png (black ink on white) and DIR/<shape>/contact.png
(all views in a grid, the seeds visible in each view drawn as red dots), so a person can check
the drawings before an analysis. The seeds are this command's own draw (30 per shape, the
paper's count; `analyze` draws 90, of which the paper method reads the first 30, and the
default method reads none: it matches every window). Shapes that cannot be drawn are listed on stderr and skipped.
"""
from __future__ import annotations

import os
import re
import sys
import time

import numpy as np
from skimage import draw, io

from ..drawings import ShapeDrawings
from ..meshes import InputError
from ..options import suggestive_problem
from ..params import DrawingSettings
from . import batch, scene

CONTACT_COLUMNS = 4
SEED_RADIUS = 2.5


def load_meshes(path: str, collection: str | None):
    """Meshes of a .blend (optionally one collection) or of a folder of mesh files."""
    if os.path.isdir(path):
        if collection:
            raise InputError("--collection only applies to a .blend INPUT")
        return scene.import_mesh_files(path)
    if path.lower().endswith(".blend"):
        return scene.meshes_from_blend(path, collection)
    raise InputError(f"{path}: not a .blend file or a folder of mesh files")


def safe_name(name: str) -> str:
    """A folder name for a shape: path separators and odd characters become '_'."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._") or "shape"


def ink_to_png(ink: np.ndarray) -> np.ndarray:
    """Ink (1 = line) to an 8-bit grey image, black lines on white paper."""
    return np.round(255.0 * (1.0 - np.clip(ink, 0.0, 1.0))).astype(np.uint8)


def contact_sheet(d: ShapeDrawings, columns: int = CONTACT_COLUMNS) -> np.ndarray:
    """RGB grid of every view with its visible seeds as red dots (1 px grey gutters)."""
    n, h, w = d.images.shape
    rows = -(-n // columns)
    sheet = np.full((rows * (h + 1) + 1, columns * (w + 1) + 1, 3), 160, np.uint8)
    for v in range(n):
        tile = np.repeat(ink_to_png(d.images[v])[:, :, None], 3, axis=2)
        for x, y in d.seed_pixels[v][d.seed_visible[v]]:
            rr, cc = draw.disk((y, x), SEED_RADIUS, shape=(h, w))
            tile[rr, cc] = (220, 30, 30)
        r, c = divmod(v, columns)
        sheet[1 + r * (h + 1):1 + r * (h + 1) + h, 1 + c * (w + 1):1 + c * (w + 1) + w] = tile
    return sheet


def write_shape(out: str, d: ShapeDrawings) -> str:
    folder = os.path.join(out, safe_name(d.name))
    os.makedirs(folder, exist_ok=True)
    for v in range(d.n_views):
        io.imsave(os.path.join(folder, f"view_{v:02d}.png"), ink_to_png(d.images[v]),
                  check_contrast=False)
    io.imsave(os.path.join(folder, "contact.png"), contact_sheet(d), check_contrast=False)
    return folder


def run(args) -> int:
    out = os.path.abspath(args.out)
    if os.path.exists(out) and not os.path.isdir(out):
        raise InputError(f"{out}: exists and is not a folder")
    suggestive = bool(getattr(args, "suggestive_contours", False))
    if suggestive and args.renderer != "freestyle":
        raise InputError(suggestive_problem(args.renderer))
    meshes = load_meshes(os.path.abspath(args.input), getattr(args, "collection", None))
    settings = DrawingSettings(renderer=args.renderer, up=args.up, suggestive_contours=suggestive)
    cache_dir = getattr(args, "cache", None)

    def progress(stage, done, total):
        if stage == "render" and total:
            print(f"\rrendering {done}/{total}", end="" if done < total else "\n",
                  file=sys.stderr, flush=True)

    t0 = time.time()
    with batch.use_scheduler(getattr(args, "scheduler", None)):
        drawings, skipped = batch.draw_collection(meshes, settings, cache_dir=cache_dir,
                                                  jobs=getattr(args, "jobs", 0), progress=progress)
    for name, reason in skipped:
        print(f"warning: skipped '{name}': {reason}", file=sys.stderr)
    if not drawings:
        raise InputError("no shape could be drawn")
    folders = {}
    for d in drawings:
        folder = safe_name(d.name)
        if folder in folders:
            raise InputError(f"shapes '{folders[folder]}' and '{d.name}' would share the folder "
                             f"'{folder}': rename one")
        folders[folder] = d.name
    os.makedirs(out, exist_ok=True)
    for d in drawings:
        write_shape(out, d)
    print(f"drew {len(drawings)} shapes ({settings.renderer}) in {time.time() - t0:.1f} s -> {out}",
          file=sys.stderr)
    return 0
