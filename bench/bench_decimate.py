"""Style-preserving vs plain decimation at 70% reduction (paper section 5.3), with Blender's
Decimate modifier, at EQUAL total triangle count.

For each mesh: the style-preserving modifier (hard: style weight 1 never collapses; soft: style
collapses last) is run at the requested ratio, then the plain modifier is tuned to the same total
triangle count. Reported per region (style = triangles whose mean vertex style weight > 0.5, the
rest): triangles kept, and geometric error = distance from points sampled uniformly on the original
surface of that region to the decimated surface (BVHTree.find_nearest), as a fraction of the
bounding-box diagonal (x 1e-3).

Weights: the sample collection's true decorative faces (`truth['face_mask']`) turned into vertex
weights (1 on every vertex of a decorative face) plus one synthetic control mesh, or with
--blend FILE the `style_weight` groups
that Analyse Style wrote into a saved file.

    .venv/bin/python bench/bench_decimate.py [--shapes 6] [--ratio 0.3] [--blend FILE]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))   # a script, not the extension

import bpy  # noqa: E402
from mathutils import Vector  # noqa: E402
from mathutils.bvhtree import BVHTree  # noqa: E402

from style_coanalysis.blender import decimate, writeback  # noqa: E402


def object_from_sample(mesh) -> bpy.types.Object:
    me = bpy.data.meshes.new(mesh.name)
    me.from_pydata(mesh.vertices.tolist(), [], mesh.faces.tolist())
    obj = bpy.data.objects.new(mesh.name, me)
    bpy.context.scene.collection.objects.link(obj)
    w = np.zeros(len(mesh.vertices), np.float32)
    w[mesh.faces[np.asarray(mesh.truth["face_mask"], bool)].ravel()] = 1.0
    writeback.set_group_weights(obj, writeback.GROUP, w)
    return obj


def bumpy_plate(n=60, seed=0) -> bpy.types.Object:
    """A controlled case: a noisy height field (every collapse costs something) whose style region
    is one quarter of the plate, i.e. a quarter of the triangles."""
    rng = np.random.default_rng(seed)
    xs = np.linspace(-1, 1, n + 1)
    X, Y = np.meshgrid(xs, xs)
    verts = np.stack([X.ravel(), Y.ravel(), 0.03 * rng.standard_normal(X.size)], 1)
    q = np.arange(n * (n + 1)).reshape(n, n + 1)[:, :n].ravel()
    quads = np.stack([q, q + 1, q + n + 2, q + n + 1], 1)
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    me = bpy.data.meshes.new("synthetic_plate")
    me.from_pydata(verts.tolist(), [], tris.tolist())
    obj = bpy.data.objects.new(me.name, me)
    bpy.context.scene.collection.objects.link(obj)
    w = ((verts[:, 0] > 0) & (verts[:, 1] > 0)).astype(np.float32)
    writeback.set_group_weights(obj, writeback.GROUP, w)
    return obj


def arrays(obj, mesh):
    """(vertices, triangles, per-vertex style weight) of a mesh in object space."""
    mesh.calc_loop_triangles()
    v = np.empty(len(mesh.vertices) * 3, np.float64)
    mesh.vertices.foreach_get("co", v)
    t = np.empty(len(mesh.loop_triangles) * 3, np.int32)
    mesh.loop_triangles.foreach_get("vertices", t)
    return v.reshape(-1, 3), t.reshape(-1, 3), writeback.vertex_weights(obj, mesh)


def sample_points(v, t, n, rng):
    """n points uniformly on the surface of triangles t."""
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    if len(t) == 0 or area.sum() <= 0:
        return np.zeros((0, 3))
    k = rng.choice(len(t), size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    return ((1 - s)[:, None] * a[k] + (s * (1 - r2))[:, None] * b[k] + (s * r2)[:, None] * c[k])


def distances(points, tree):
    return np.array([(tree.find_nearest(Vector(p))[3] or 0.0) for p in points])


def measure(obj, original, n_points, seed):
    """Triangles kept and surface error per region for the object's current modifier stack."""
    v0, t0, w0 = original
    style0 = w0[t0].mean(1) > writeback.THRESHOLD
    dg = bpy.context.evaluated_depsgraph_get()
    dg.update()
    ev = obj.evaluated_get(dg)
    me = ev.to_mesh()
    try:
        v1, t1, w1 = arrays(obj, me)
    finally:
        ev.to_mesh_clear()
    style1 = w1[t1].mean(1) > writeback.THRESHOLD
    tree = BVHTree.FromPolygons(v1.tolist(), t1.tolist())
    diag = np.linalg.norm(np.ptp(v0, axis=0))
    rng = np.random.default_rng(seed)
    out = {"tris": len(t1), "style_tris": int(style1.sum()), "rest_tris": int((~style1).sum())}
    for region, mask in (("style", style0), ("rest", ~style0)):
        n = int(round(n_points * mask.mean())) if mask.any() else 0
        d = distances(sample_points(v0, t0[mask], max(n, 1), rng), tree) / diag if n else []
        out[f"{region}_mean"] = float(np.mean(d)) if len(d) else float("nan")
        out[f"{region}_max"] = float(np.max(d)) if len(d) else float("nan")
    return out


def run(objects, ratio, strength, n_points):
    rows = []
    for obj in objects:
        original = arrays(obj, obj.data)
        style0 = original[2][original[1]].mean(1) > writeback.THRESHOLD
        base = {"name": obj.name, "before": len(original[1]), "style_before": int(style0.sum())}
        for kind, hard in (("hard", True), ("soft", False)):
            t = time.perf_counter()
            sp = decimate.add_decimate(obj, ratio, strength, style_preserving=True, hard=hard)
            t_sp = time.perf_counter() - t
            m_sp = measure(obj, original, n_points, seed=1)
            t = time.perf_counter()
            decimate.match_plain_to(obj, sp["triangles"])
            t_pl = time.perf_counter() - t
            m_pl = measure(obj, original, n_points, seed=1)
            rows.append(base | {"method": f"style-{kind}", "sec": t_sp} | m_sp)
            rows.append(base | {"method": f"plain@{kind}", "sec": t_pl} | m_pl)
            decimate.remove_decimate(obj)
    return rows


def table(rows, ratio):
    head = (f"{'mesh':<22}{'method':<12}{'tris':>12}{'style kept':>16}{'rest kept':>15}"
            f"{'style err mean/max':>21}{'rest err mean/max':>20}{'sec':>6}")
    print(f"\nDecimation to ratio {ratio:.2f} ({100 * (1 - ratio):.0f}% reduction asked); plain "
          "tuned to the style-preserving count. Errors: x1e-3 of the bbox diagonal.")
    print(head)
    print("-" * len(head))

    def pct(a, b):
        return f"{a}/{b} {100 * a / b:3.0f}%" if b else f"{a}/0"

    for r in rows:
        print(f"{r['name'][:21]:<22}{r['method']:<12}{r['tris']:>6}/{r['before']:<5}"
              f"{pct(r['style_tris'], r['style_before']):>16}"
              f"{pct(r['rest_tris'], r['before'] - r['style_before']):>15}"
              f"{1e3 * r['style_mean']:>10.2f}/{1e3 * r['style_max']:<9.2f}"
              f"{1e3 * r['rest_mean']:>10.2f}/{1e3 * r['rest_max']:<9.2f}{r['sec']:>6.2f}")
    print("\nMeans over meshes (error x1e-3 of the diagonal):")
    for method in dict.fromkeys(r["method"] for r in rows):
        sel = [r for r in rows if r["method"] == method]
        kept = np.mean([r["style_tris"] / max(r["style_before"], 1) for r in sel])
        total = np.mean([r["tris"] / r["before"] for r in sel])
        print(f"  {method:<12} total kept {100 * total:5.1f}%  style kept {100 * kept:5.1f}%  "
              f"style err mean {1e3 * np.nanmean([r['style_mean'] for r in sel]):6.2f} "
              f"max {1e3 * np.nanmean([r['style_max'] for r in sel]):6.2f}  "
              f"rest err mean {1e3 * np.nanmean([r['rest_mean'] for r in sel]):6.2f} "
              f"max {1e3 * np.nanmean([r['rest_max'] for r in sel]):6.2f}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--shapes", type=int, default=6, help="sample shapes (default 6)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--ratio", type=float, default=0.3, help="triangles to keep (0.3: 70%% off)")
    p.add_argument("--strength", type=float, default=1.0, help="vertex group factor")
    p.add_argument("--points", type=int, default=20000, help="surface samples per mesh")
    p.add_argument("--blend", help="a .blend with analysed meshes (style_weight groups)")
    args = p.parse_args(argv)

    if args.blend:
        bpy.ops.wm.open_mainfile(filepath=args.blend, load_ui=False)
        objects = [o for o in bpy.context.scene.objects
                   if o.type == "MESH" and o.vertex_groups.get(writeback.GROUP)]
        source = args.blend
    else:
        from style_coanalysis import sample
        bpy.ops.wm.read_factory_settings(use_empty=True)
        objects = [object_from_sample(m) for m in sample.generate(args.shapes, args.seed)]
        objects.append(bumpy_plate())
        source = (f"sample.generate({args.shapes}, seed={args.seed}) with their true decorative "
                  "faces, plus a synthetic noisy plate whose style region is one quarter")
    names = [o.name for o in objects]
    print(f"{len(names)} meshes from {source}")
    t = time.perf_counter()
    rows = run([bpy.data.objects[n] for n in names], args.ratio, args.strength, args.points)
    table(rows, args.ratio)
    print(f"\ntotal {time.perf_counter() - t:.1f} s")


if __name__ == "__main__":
    main()
