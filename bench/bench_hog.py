"""HOG maps: `features.hog_images` against `skimage.feature.hog`, the library whose numbers it
computes, on every drawing of benchmark collections: time per view and whether every number is
the same.

Run with `python bench/bench_hog.py [--collections sample-120 collection2 hu2017-all]`.
Drawings come from the user cache (`bench/generalisation.py`'s collections; shapes not cached
yet are rendered). One process, one shape's views at a time, as the job computes them. Prints a
table; asserts nothing.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from skimage.feature import hog

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from style_coanalysis.evaluation import benchmark as B  # noqa: E402
from style_coanalysis.features import CELLS_PER_BLOCK, ORIENTATIONS, PIXELS_PER_CELL, hog_images  # noqa: E402


def skimage_maps(images: np.ndarray) -> np.ndarray:
    """The library's maps of one shape's views, one call per view."""
    cell, block = (PIXELS_PER_CELL,) * 2, (CELLS_PER_BLOCK,) * 2
    out = [hog(im, orientations=ORIENTATIONS, pixels_per_cell=cell, cells_per_block=block,
               block_norm="L2-Hys", feature_vector=False) for im in images]
    return np.stack([o.reshape(o.shape[0], o.shape[1], -1) for o in out])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--collections", nargs="*", default=["sample-120", "collection2", "hu2017-all"])
    args = ap.parse_args()
    print("| collection | shapes | views | hog_images ms/view | skimage ms/view | speed-up "
          "| shapes with any number different |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name in args.collections:
        coll = B.load_collection(name)
        t_ours = t_lib = 0.0
        views = differ = 0
        for d in coll.drawings:
            images = np.asarray(d.images, np.float32)
            t = time.perf_counter()
            ours = hog_images(images)
            t_ours += time.perf_counter() - t
            t = time.perf_counter()
            lib = skimage_maps(images)
            t_lib += time.perf_counter() - t
            views += len(images)
            differ += int(not np.array_equal(ours, lib))
        print(f"| {name} | {len(coll.drawings)} | {views} | {1e3 * t_ours / views:.2f} "
              f"| {1e3 * t_lib / views:.2f} | {t_lib / t_ours:.2f}x | {differ} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
