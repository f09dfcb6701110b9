"""Renderer benchmark: speed, Freestyle/Line Art agreement, cost vs face count, suggestive contours.

Run with `nice .venv/bin/python bench/bench_render.py [--shapes 6]`. Everything runs in one
process, one shape at a time (no cache, no workers), so the ratios compare like with like.
Prints tables; asserts nothing.
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from scipy import ndimage

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import bpy  # noqa: E402

from style_coanalysis.blender.render import draw_shape  # noqa: E402
from style_coanalysis.meshes import Mesh, normalise  # noqa: E402
from style_coanalysis.params import DrawingSettings  # noqa: E402

INK = 0.25          # an ink pixel: alpha above this


def f_score(a: np.ndarray, b: np.ndarray, radius: float = 2.0) -> float:
    """Symmetric agreement of two ink masks (precision/recall of ink within `radius` px)."""
    if not a.any() or not b.any():
        return float(a.any() == b.any())
    precision = (ndimage.distance_transform_edt(~b)[a] <= radius).mean()
    recall = (ndimage.distance_transform_edt(~a)[b] <= radius).mean()
    return float(2 * precision * recall / (precision + recall))


def sample_meshes(n: int) -> list[Mesh]:
    try:
        from style_coanalysis import sample
        return sample.generate(size=n, seed=0)
    except Exception as exc:  # the sample generator is someone else's module: fall back
        print(f"(sample collection unavailable: {exc}; using spheres)")
        return [sphere(16 + 8 * i) for i in range(n)]


def sphere(segments: int, name: str = "") -> Mesh:
    """A UV sphere with a flattened top: silhouettes and a crease ring, 2*s*(s-1) triangles."""
    import bmesh
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=segments, radius=1.0)
    bmesh.ops.triangulate(bm, faces=bm.faces)
    v = np.array([x.co[:] for x in bm.verts], np.float64)
    f = np.array([[x.index for x in face.verts] for face in bm.faces], np.int32)
    bm.free()
    v[:, 2] = np.where(v[:, 2] > 0.5, 0.5 + 0.3 * (v[:, 2] - 0.5), v[:, 2])   # a flattened top
    return Mesh(name or f"sphere{len(f)}", v, f)


def timed(mesh: Mesh, settings: DrawingSettings):
    t = time.perf_counter()
    d = draw_shape(mesh, settings)
    return d, time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--shapes", type=int, default=6, help="shapes of the sample collection")
    args = ap.parse_args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    meshes = [normalise(m) for m in sample_meshes(args.shapes)]
    fs_set, la_set = DrawingSettings(renderer="freestyle"), DrawingSettings(renderer="lineart")
    draw_shape(meshes[0], la_set)     # warm-up (first Cycles/Line Art use loads kernels)

    print(f"\n## Speed and agreement on {len(meshes)} sample shapes (200x200, 12 views)")
    print(f"{'shape':28s} {'faces':>7s} {'FS s':>6s} {'LA s':>6s} {'F2px':>6s} {'seed vis':>8s}")
    from style_coanalysis.blender.render import draw_lines
    t_fs = t_la = l_fs = l_la = 0.0
    scores, vis = [], []
    for m in meshes:
        dfs, tf = timed(m, fs_set)
        dla, tl = timed(m, la_set)
        t_fs, t_la = t_fs + tf, t_la + tl
        t = time.perf_counter()
        draw_lines(m, fs_set)
        t_mid = time.perf_counter()
        draw_lines(m, la_set)
        l_fs, l_la = l_fs + t_mid - t, l_la + time.perf_counter() - t_mid
        f = np.mean([f_score(dfs.images[v] > INK, dla.images[v] > INK) for v in range(dfs.n_views)])
        scores.append(f)
        vis.append(dfs.seed_visible.mean())
        print(f"{m.name:28s} {len(m.faces):7d} {tf:6.2f} {tl:6.2f} {f:6.3f} {vis[-1]:8.2f}")
    views = 12 * len(meshes)
    print(f"\nlines only (the renderers themselves): Freestyle {views / l_fs:6.1f} views/s   "
          f"Line Art {views / l_la:6.1f} views/s   ratio {l_fs / l_la:4.1f}x")
    print(f"whole drawing step (+ seeds and ray-cast visibility, the same for both): Freestyle "
          f"{views / t_fs:6.1f} views/s   Line Art {views / t_la:6.1f} views/s   ratio {t_fs / t_la:4.1f}x")
    print(f"agreement F-score (2 px, mean over views): {np.mean(scores):.3f} "
          f"(min shape {np.min(scores):.3f})")
    print(f"seed visibility rate (seeds visible per view): {np.mean(vis):.3f}")

    print("\n## Time per shape (12 views) vs face count")
    print(f"{'faces':>7s} {'FS s':>6s} {'LA s':>6s} {'FS+SC s':>8s} {'vis s':>6s}")
    from style_coanalysis.blender import render
    for segments in (32, 64, 128):                # about 2k, 8k and 32k triangles
        m = normalise(sphere(segments))
        _, tf = timed(m, fs_set)
        _, tl = timed(m, la_set)
        _, ts = timed(m, DrawingSettings(renderer="freestyle", suggestive_contours=True))
        t = time.perf_counter()
        tree = render._bvh(m)
        render.ray_visibility(tree, render.rig_for(fs_set), m.vertices, faces=m.faces)
        tv = time.perf_counter() - t
        print(f"{len(m.faces):7d} {tf:6.2f} {tl:6.2f} {ts:8.2f} {tv:6.2f}")


if __name__ == "__main__":
    main()
