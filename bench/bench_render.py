"""Renderer benchmark: the whole drawing step (lines, seeds, visibility) of Freestyle, Line Art
and zbuffer, their agreement with Freestyle, cost vs face count, suggestive contours.

Run with `nice .venv/bin/python bench/bench_render.py [--shapes 6] [--real DIR --up y]`.
Everything runs in one process, one shape at a time, one render thread (no cache, no workers),
so the ratios compare like with like. Prints tables; asserts nothing.
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

from style_coanalysis.blender.render import draw_shape, quarter_trees, ray_visibility, rig_for  # noqa: E402
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


CPU: dict = {}      # renderer -> processor seconds (all threads of this process), summed


def timed(mesh: Mesh, settings: DrawingSettings):
    """Drawings and wall seconds; processor seconds are added to CPU[renderer] (on a shared
    machine the wall clock also counts the other sessions' work)."""
    t, c = time.perf_counter(), time.process_time()
    d = draw_shape(mesh, settings, threads=1)
    CPU[settings.renderer] = CPU.get(settings.renderer, 0.0) + time.process_time() - c
    return d, time.perf_counter() - t


RENDERERS = ("freestyle", "lineart", "zbuffer")


def compare(meshes: list[Mesh], title: str) -> None:
    """Whole drawing step per renderer (lines, seeds, visibility), one thread each, and each
    renderer's agreement with Freestyle: lines (F-score within 2 px), and the zbuffer path's seed
    visibility against the BVH ray casts of the other renderers."""
    sets = {r: DrawingSettings(renderer=r) for r in RENDERERS}
    print(f"\n## {title}: whole drawing step (12 views, seeds, visibility), 1 thread")
    print(f"{'shape':28s} {'faces':>7s} {'FS s':>6s} {'LA s':>6s} {'ZB s':>6s} {'F LA':>6s} "
          f"{'F ZB':>6s} {'vis ZB':>6s}")
    total = dict.fromkeys(RENDERERS, 0.0)
    CPU.clear()
    f_la, f_zb, vis = [], [], []
    for m in meshes:
        out, took = {}, {}
        for r in RENDERERS:
            out[r], took[r] = timed(m, sets[r])
            total[r] += took[r]
        ref = out["freestyle"]
        f_la.append(np.mean([f_score(ref.images[v] > INK, out["lineart"].images[v] > INK)
                             for v in range(ref.n_views)]))
        f_zb.append(np.mean([f_score(ref.images[v] > INK, out["zbuffer"].images[v] > INK)
                             for v in range(ref.n_views)]))
        zb = out["zbuffer"]
        rig = rig_for(sets["zbuffer"])
        rays = ray_visibility(quarter_trees(m, rig), rig, zb.seeds, own_face=zb.seed_faces)
        vis.append(float((zb.seed_visible == rays).mean()))
        print(f"{m.name[:28]:28s} {len(m.faces):7d} " + " ".join(f"{took[r]:6.2f}" for r in RENDERERS)
              + f" {f_la[-1]:6.3f} {f_zb[-1]:6.3f} {vis[-1]:6.3f}", flush=True)
    fs = total["freestyle"]
    print("whole step, Freestyle over the others (same run), wall clock: "
          + ", ".join(f"{r} {fs / total[r]:.1f}x" for r in RENDERERS[1:])
          + "; processor time: " + ", ".join(f"{r} {CPU['freestyle'] / CPU[r]:.1f}x"
                                              for r in RENDERERS[1:]))
    print(f"lines vs Freestyle's, F-score within 2 px (mean over views, then shapes): Line Art "
          f"{np.mean(f_la):.3f} (min {np.min(f_la):.3f}), zbuffer {np.mean(f_zb):.3f} "
          f"(min {np.min(f_zb):.3f})")
    print(f"seed visibility, zbuffer's depth buffers vs the ray casts: {np.mean(vis):.4f} of "
          f"(view, seed) pairs agree (min shape {np.min(vis):.4f})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--shapes", type=int, default=6, help="shapes of the sample collection")
    ap.add_argument("--real", default=None, help="also a folder of real mesh files (OBJ...)")
    ap.add_argument("--up", default="y", help="up axis of the --real meshes (default y)")
    args = ap.parse_args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    meshes = [normalise(m) for m in sample_meshes(args.shapes)]
    for r in RENDERERS:                # warm-up (first Cycles/Line Art use loads kernels)
        draw_shape(meshes[0], DrawingSettings(renderer=r))
    compare(meshes, f"{len(meshes)} sample shapes")
    if args.real:
        from style_coanalysis.blender.scene import import_mesh_files
        real = sorted(import_mesh_files(args.real), key=lambda m: m.name)
        compare([normalise(m, args.up) for m in real], f"{len(real)} real meshes ({args.real})")

    print("\n## Time per shape (12 views, whole step, 1 thread) vs face count")
    print(f"{'faces':>7s} {'FS s':>6s} {'LA s':>6s} {'ZB s':>6s} {'FS+SC s':>8s}")
    for segments in (32, 64, 128):                # about 2k, 8k and 32k triangles
        m = normalise(sphere(segments))
        took = [timed(m, DrawingSettings(renderer=r))[1] for r in RENDERERS]
        _, ts = timed(m, DrawingSettings(renderer="freestyle", suggestive_contours=True))
        print(f"{len(m.faces):7d} " + " ".join(f"{t:6.2f}" for t in took) + f" {ts:8.2f}")


if __name__ == "__main__":
    main()
