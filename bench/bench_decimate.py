"""Style-preserving vs plain decimation at 70% reduction (paper section 5.3), with Blender's
Decimate modifier, at EQUAL total triangle count.

For each mesh: the style-preserving modifier (hard: style weight 1 never collapses; soft: style
collapses last; split: the plain part decimated first to its own lower target, then the style
part to the rest of the budget, `decimate.add_split_decimate`) is run at the requested ratio,
then the plain modifier is tuned to the same total triangle count. Reported per region: triangles kept (style = mean vertex style weight > 0.5,
what the decimated mesh still carries), and geometric error (style = the generator's TRUE
decorative faces when the mesh comes from a generated collection, else the weights' region):
the distance from points sampled uniformly on the original surface of that region to the
decimated surface (BVHTree.find_nearest), as a fraction of the bounding-box diagonal (x 1e-3). "bound" is what no redistribution can beat at that count: the
style triangles plain decimation kept plus every triangle it kept outside the style region.

Weights: the collection's true decorative faces (`truth['face_mask']`) turned into vertex
weights (1 on every vertex of a decorative face) plus one synthetic control mesh, or with
--blend FILE the `style_weight` groups that Analyse Style wrote into a saved file (scored
against the truth of `sample.generate(120, 0)` for the objects it names). `--picture PNG`
draws the first mesh before, after style-preserving (split) and after plain decimation.

    .venv/bin/python bench/bench_decimate.py [--collection sample|collection2] [--shapes 6]
        [--ratio 0.3] [--blend FILE] [--picture PNG]
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


TRUTH: dict = {}        # object name -> true decorative triangles (generated collections)


def object_from_sample(mesh) -> bpy.types.Object:
    me = bpy.data.meshes.new(mesh.name)
    me.from_pydata(mesh.vertices.tolist(), [], mesh.faces.tolist())
    obj = bpy.data.objects.new(mesh.name, me)
    bpy.context.scene.collection.objects.link(obj)
    w = np.zeros(len(mesh.vertices), np.float32)
    w[mesh.faces[np.asarray(mesh.truth["face_mask"], bool)].ravel()] = 1.0
    writeback.set_group_weights(obj, writeback.GROUP, w)
    TRUTH[obj.name] = np.asarray(mesh.truth["face_mask"], bool)
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
    style0 = style_region(obj.name, t0, w0)
    v1, t1, w1 = evaluated_arrays(obj)
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


def style_region(name, t0, w0):
    """The true decorative triangles when known (same triangle count), else weight > 0.5."""
    truth = TRUTH.get(name)
    if truth is not None and len(truth) == len(t0):
        return truth
    return w0[t0].mean(1) > writeback.THRESHOLD


def run(objects, ratio, strength, n_points, picture=None):
    rows = []
    for k, obj in enumerate(objects):
        original = arrays(obj, obj.data)
        # triangle counts follow the weights (the only thing a decimated mesh still carries)
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
            m_pl["bound"] = m_pl["style_tris"] + m_pl["rest_tris"]
            rows.append(base | {"method": f"style-{kind}", "sec": t_sp} | m_sp)
            rows.append(base | {"method": f"plain@{kind}", "sec": t_pl} | m_pl)
            decimate.remove_decimate(obj)
        t = time.perf_counter()
        sp = decimate.add_split_decimate(obj, ratio)
        t_sp = time.perf_counter() - t
        m_sp = measure(obj, original, n_points, seed=1)
        decimate.remove_decimate(obj)
        t = time.perf_counter()
        decimate.match_plain_to(obj, sp["triangles"])
        t_pl = time.perf_counter() - t
        m_pl = measure(obj, original, n_points, seed=1)
        m_pl["bound"] = m_pl["style_tris"] + m_pl["rest_tris"]
        rows.append(base | {"method": "style-split", "sec": t_sp} | m_sp)
        rows.append(base | {"method": "plain@split", "sec": t_pl} | m_pl)
        decimate.remove_decimate(obj)
        if picture is not None and k == 0:
            draw_picture(obj, original, style_region(obj.name, original[1], original[2]),
                         ratio, picture)
    return rows


def evaluated_arrays(obj):
    """(vertices, triangles, style weights) of the object after its modifier stack."""
    return decimate.evaluated(obj, arrays)


def draw_picture(obj, original, style0, ratio, path):
    """Original | style-preserving (split) | plain at the same count: flat-shaded from one rig
    view with every triangle's edges drawn (so the triangle density shows), the true style
    region in orange on the original."""
    from PIL import Image, ImageDraw
    from style_coanalysis.report import GREY, ORANGE
    from style_coanalysis.rig import Rig, project
    v0, t0, _ = original
    decimate.add_split_decimate(obj, ratio)
    sp = evaluated_arrays(obj)[:2]
    decimate.remove_decimate(obj)
    decimate.match_plain_to(obj, len(sp[1]))
    pl = evaluated_arrays(obj)[:2]
    centre = v0.mean(axis=0)
    radius = np.linalg.norm(v0 - centre, axis=1).max()
    cam = Rig(image_size=400).matrices()[1]
    panels = []
    for (v, t), title, colours in (((v0, t0), f"original {len(t0)}", style0),
                                   (sp, f"style-preserving {len(sp[1])}", None),
                                   (pl, f"plain {len(pl[1])}", None)):
        vn = (v - centre) / radius
        pix, depth = project(cam[None], vn)
        pix, depth = pix[0], depth[0]
        tri = vn[t]
        nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-12)
        light = 0.35 + 0.65 * np.abs(nrm @ np.array([0.3, -0.8, 0.5]) / np.linalg.norm([0.3, -0.8, 0.5]))
        img = Image.new("RGB", (400, 420), (255, 255, 255))
        draw = ImageDraw.Draw(img)
        for f in np.argsort(-depth[t].mean(axis=1)):
            base = ORANGE if colours is not None and colours[f] else GREY
            fill = tuple(int(c) for c in base * light[f])
            draw.polygon([tuple(p) for p in pix[t[f]]], fill=fill, outline=(60, 60, 60))
        draw.text((8, 402), title, fill=(0, 0, 0))
        panels.append(img)
    out = Image.new("RGB", (1200, 420), (255, 255, 255))
    for i, p in enumerate(panels):
        out.paste(p, (400 * i, 0))
    out.save(path)
    print(f"picture: {path} ({obj.name})")
    decimate.remove_decimate(obj)


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
    print("\nMeans over the collection's meshes, the synthetic plate left out (error x1e-3 of the "
          "diagonal; bound: the most style triangles any method can keep at plain's count):")
    for method in dict.fromkeys(r["method"] for r in rows):
        sel = [r for r in rows if r["method"] == method and r["name"] != "synthetic_plate"]
        if not sel:
            continue
        kept = np.mean([r["style_tris"] / max(r["style_before"], 1) for r in sel])
        total = np.mean([r["tris"] / r["before"] for r in sel])
        bound = (f" (bound {100 * np.mean([min(r['bound'], r['style_before']) / max(r['style_before'], 1) for r in sel]):5.1f}%)"
                 if "bound" in sel[0] else "")
        print(f"  {method:<12} total kept {100 * total:5.1f}%  style kept {100 * kept:5.1f}%{bound}  "
              f"style err mean {1e3 * np.nanmean([r['style_mean'] for r in sel]):6.2f} "
              f"max {1e3 * np.nanmean([r['style_max'] for r in sel]):6.2f}  "
              f"rest err mean {1e3 * np.nanmean([r['rest_mean'] for r in sel]):6.2f} "
              f"max {1e3 * np.nanmean([r['rest_max'] for r in sel]):6.2f}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--collection", default="sample", choices=["sample", "collection2"])
    p.add_argument("--shapes", type=int, default=6, help="shapes of the collection (default 6)")
    p.add_argument("--picture", help="PNG: the first mesh before / style-preserving / plain")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--ratio", type=float, default=0.3, help="triangles to keep (0.3: 70%% off)")
    p.add_argument("--strength", type=float, default=1.0, help="vertex group factor")
    p.add_argument("--points", type=int, default=20000, help="surface samples per mesh")
    p.add_argument("--blend", help="a .blend with analysed meshes (style_weight groups)")
    args = p.parse_args(argv)

    if args.blend:
        bpy.ops.wm.open_mainfile(filepath=args.blend, load_ui=False)
        objects = [o for o in bpy.context.scene.objects
                   if o.type == "MESH" and o.vertex_groups.get(writeback.GROUP)][:args.shapes]
        from style_coanalysis import sample
        TRUTH.update({m.name: np.asarray(m.truth["face_mask"], bool) for m in sample.generate(120, 0)})
        source = f"{args.blend} (first {args.shapes} analysed objects)"
    else:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        if args.collection == "sample":
            from style_coanalysis.sample import generate
            meshes = generate(args.shapes, args.seed)
        else:
            from style_coanalysis.evaluation.collection2 import generate
            meshes = generate(size=args.shapes, seed=args.seed)
        objects = [object_from_sample(m) for m in meshes]
        objects.append(bumpy_plate())
        source = (f"{args.collection}.generate({args.shapes}, seed={args.seed}) with their true decorative "
                  "faces, plus a synthetic noisy plate whose style region is one quarter")
    names = [o.name for o in objects]
    print(f"{len(names)} meshes from {source}")
    t = time.perf_counter()
    rows = run([bpy.data.objects[n] for n in names], args.ratio, args.strength, args.points,
               args.picture)
    table(rows, args.ratio)
    print(f"\ntotal {time.perf_counter() - t:.1f} s")


if __name__ == "__main__":
    main()
