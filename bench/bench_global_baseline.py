"""Global-shape baseline (bounding-box proportions, face count, area -> standardise -> k-means):
purity against style and against category, on the sample collection and on the voxel set.

It must stay near chance on style for the sample collection (the collection was built so that
only ornament tells styles apart); on the real voxel set it shows how much style the global shape
already gives away there.

    nice .venv/bin/python bench/bench_global_baseline.py [--size 120] [--seeds 5] [--no-voxels]
        [--lines N]   # also the line-statistics baseline on N sample shapes (Line Art drawings, bpy)
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from style_coanalysis import metrics, sample  # noqa: E402
from style_coanalysis.evaluation import baselines, voxels  # noqa: E402


def report(label, feats, shapes, seeds):
    for key in ("style", "category"):
        truth = np.array([m.truth[key] for m in shapes])
        classes, counts = np.unique(truth, return_counts=True)
        k = len(classes)
        runs = [metrics.score(baselines.cluster_baseline(feats, k, s), truth) for s in range(seeds)]
        pur = np.array([r["purity"] for r in runs])
        nmi = np.mean([r["nmi"] for r in runs])
        print(f"{label:>8} {key:<9} k={k}  purity {pur.mean():.3f} +- {pur.std():.3f}  "
              f"NMI {nmi:.3f}  chance(majority share) {counts.max() / counts.sum():.3f}  "
              f"1/k {1 / k:.3f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=120)
    ap.add_argument("--seeds", type=int, default=5, help="k-means seeds (the sample's seeds are 0-2)")
    ap.add_argument("--no-voxels", action="store_true")
    ap.add_argument("--lines", type=int, default=0,
                    help="render N sample shapes with Line Art and score the line-statistics baseline")
    args = ap.parse_args()
    for gen_seed in range(3):
        t0 = time.time()
        shapes = sample.generate(args.size, seed=gen_seed)
        gen = time.time() - t0
        faces = [len(m.faces) for m in shapes]
        print(f"sample seed {gen_seed}: {len(shapes)} shapes generated in {gen:.2f} s, "
              f"{min(faces)}-{max(faces)} triangles")
        report("sample", baselines.global_shape_features(shapes), shapes, args.seeds)
    if not args.no_voxels:
        t0 = time.time()
        vox = voxels.load_hu2017()
        print(f"voxel set: {len(vox)} shapes loaded in {time.time() - t0:.1f} s")
        report("voxels", baselines.global_shape_features(vox), vox, args.seeds)
        report("vox-raw", baselines.raw_size(vox), vox, args.seeds)
    if args.lines:
        line_baseline(args.lines, args.seeds)


def line_baseline(n, seeds):
    """Ink density + orientation histogram of the 12 drawings: does plain line texture give style away?"""
    import bpy

    from style_coanalysis.blender.render import draw_shape
    from style_coanalysis.meshes import normalise
    from style_coanalysis.params import DrawingSettings

    bpy.ops.wm.read_factory_settings(use_empty=True)
    shapes = sample.generate(n, seed=0)
    t0 = time.time()
    images = [draw_shape(normalise(m), DrawingSettings(renderer="lineart")).images for m in shapes]
    print(f"line drawings of {n} shapes (Line Art) in {time.time() - t0:.1f} s")
    report("lines", baselines.line_statistics(images), shapes, seeds)


if __name__ == "__main__":
    main()
