"""All 537 Hu 2017 voxel models -> meshes: how many are watertight, vertex counts, time.

Watertight = every edge is shared by exactly two triangles (what marching cubes on a padded grid
should give). Also reports how many edges the smoothing leaves as Freestyle creases (dihedral
below 134 degrees), the staircase the smoothing is there to remove.

    nice .venv/bin/python bench/bench_voxels.py [--smooth 10] [--root ../shared/data/hu2017_vox]
"""
from __future__ import annotations

import argparse
import glob
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from style_coanalysis.evaluation import voxels  # noqa: E402


def edge_stats(v, f):
    """(watertight?, share of edges with dihedral angle below 134 degrees)."""
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    order = np.lexsort(e.T[::-1])
    e = e[order]
    _, counts = np.unique(e, axis=0, return_counts=True)
    if not np.all(counts == 2):
        return False, float("nan")
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]).astype(np.float64)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    pairs = np.tile(np.arange(len(f)), 3)[order].reshape(-1, 2)
    cos = np.einsum("ij,ij->i", n[pairs[:, 0]], n[pairs[:, 1]])
    return True, float(np.mean(cos < np.cos(np.radians(180 - 134))))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", default=voxels.DEFAULT_ROOT)
    ap.add_argument("--smooth", type=int, default=10)
    args = ap.parse_args()
    root = voxels.resolve_root(args.root)
    files = sorted(glob.glob(os.path.join(root, "voxel", "*.binvox")))
    t0 = time.time()
    tight, nverts, creases, unlabelled = 0, [], [], 0
    for p in files:
        m = voxels.voxel_mesh(p, smooth_iters=args.smooth)
        ok, share = edge_stats(m.vertices, m.faces)
        tight += ok
        if ok:
            creases.append(share)
        nverts.append(len(m.vertices))
        unlabelled += "style" not in m.truth
    dt = time.time() - t0
    print(f"models: {len(files)}  watertight: {tight}/{len(files)}  without labels: {unlabelled}")
    print(f"vertices: min {min(nverts)}  median {int(np.median(nverts))}  max {max(nverts)}")
    print(f"crease edges (<134 deg) after {args.smooth} smoothing iterations: "
          f"median {100 * np.median(creases):.1f}%")
    print(f"time: {dt:.1f} s total, {1000 * dt / len(files):.0f} ms per model")


if __name__ == "__main__":
    main()
