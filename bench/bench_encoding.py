"""Time the analysis front end (HOG maps, k-means representatives, encoding) on synthetic drawings.

    nice .venv/bin/python bench/bench_encoding.py [n_shapes] [n_views]

Prints seconds per stage for a synthetic collection (tests/synthetic.py: style motifs on
category outlines), default 120 shapes x 12 views x 50 representatives per view.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from synthetic import make_collection  # noqa: E402

from style_coanalysis.encoding import build_filter_bank, cross_view_responses, encode  # noqa: E402
from style_coanalysis.features import hog_images  # noqa: E402
from style_coanalysis.patches import extract_patches  # noqa: E402


def main(n_shapes: int = 120, n_views: int = 12, k: int = 50) -> None:
    t = time.perf_counter()
    per_cell = -(-n_shapes // 9)
    drawings = make_collection(per_cell, n_views, seed=0)[0][:n_shapes]
    print(f"{len(drawings)} shapes x {n_views} views, {k} representatives per view "
          f"(synthetic drawings made in {time.perf_counter() - t:.1f} s)")
    times = {}
    t = time.perf_counter()
    patches = extract_patches(drawings, size=48)
    times["patches"] = time.perf_counter() - t
    t = time.perf_counter()
    maps = np.stack([hog_images(d.images) for d in drawings])
    times["hog maps"] = time.perf_counter() - t
    t = time.perf_counter()
    bank = build_filter_bank(maps, patches.shape, patches.view, patches.seed, patches.centre,
                             48, k, random_state=0)
    times["k-means representatives"] = time.perf_counter() - t
    t = time.perf_counter()
    pooled = encode(maps, bank, drawings[0].images.shape[1:])
    times["encode (own view, 5 pools)"] = time.perf_counter() - t
    t = time.perf_counter()
    cross_view_responses(maps, bank, drawings[0].images.shape[1:])
    times["all filters x all views"] = time.perf_counter() - t
    print(f"{len(patches)} patches, {len(bank)} filters, encoding {pooled.shape}")
    total = sum(times.values())
    for name, sec in times.items():
        print(f"  {name:28s} {sec:7.2f} s  {100 * sec / total:5.1f} %")
    print(f"  {'total':28s} {total:7.2f} s")


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:3]))
