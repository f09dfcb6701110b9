"""Style-preserving decimation with Blender's own Decimate modifier (COLLAPSE), paper section 5.3.

Decimate scales an edge's collapse cost by the vertex group weight, and never collapses an edge
touching a vertex of group weight exactly 0 (low weight = protected). Our `style_weight` group is
1 on style regions, so the style-preserving modifier sets `invert_vertex_group=True`: vertices of
style weight 1 are never collapsed, intermediate weights cost more to collapse (scaled by
`strength` = `vertex_group_factor`), weight 0 is decimated as usual. Because protected triangles
stay, the requested ratio may be out of reach: every function reports the count actually reached.

When the style regions hold most of the triangles (finely carved parts often do), hard protection
cannot get anywhere near the requested ratio. `hard=False` drives the modifier with a derived group
`style_weight_soft` (the weights capped at SOFT_CAP < 1): no vertex is then untouchable, but
style edges cost far more to collapse, so the ratio is reached by decimating the rest first.

`add_split_decimate` is the third way, the issue's "separate targets": the plain part (triangles
outside the style regions) is decimated first to its own, lower target with the style part frozen,
then the style part takes the rest of the budget with the plain part frozen. Each pass is plain
quadric decimation inside its part (group weights exactly 0 or 1), so the style part's collapses
are chosen by geometric error alone; the soft group's weights below 1 add a cost that grows with
edge length (Blender's modifier), which is why the soft mode can lose to plain decimation in the
style region at the same count (bench/bench_decimate.py).

One decimation per object at a time: adding the style-preserving modifier removes the plain one
and vice versa (stacking both would decimate twice). Compare the two on duplicates, or one after
the other as `match_plain_to` and the bench do.

A triangle is "style" when the mean style weight of its three vertices is > 0.5 (the same rule as
the highlight material). After decimation the weights are read from the evaluated mesh, which keeps
the vertex group on the surviving vertices.
"""
from __future__ import annotations

import bpy
import numpy as np

from .writeback import GROUP, SOFT_GROUP, THRESHOLD, set_group_weights, vertex_weights

SOFT_CAP = 0.99
STYLE_MODIFIER = "Style Decimate"
PLAIN_MODIFIER = "Plain Decimate"
SPLIT_MODIFIERS = ("Style Decimate: plain part", "Style Decimate: style part")
SPLIT_GROUPS = ("style_split_plain", "style_split_style")


def triangle_counts(obj, mesh=None, group: str = GROUP) -> tuple[int, int]:
    """(all triangles, style triangles) of `mesh` (default: the object's own, unevaluated mesh)."""
    mesh = mesh if mesh is not None else obj.data
    mesh.calc_loop_triangles()
    n = len(mesh.loop_triangles)
    if n == 0:
        return 0, 0
    tris = np.empty(n * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    weights = vertex_weights(obj, mesh, group)
    style = weights[tris.reshape(-1, 3)].mean(axis=1) > THRESHOLD
    return n, int(style.sum())


def evaluated(obj, read, depsgraph=None):
    """`read(obj, mesh)` of the object's mesh after its modifier stack (a temporary mesh,
    freed afterwards)."""
    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    depsgraph.update()
    obj_eval = obj.evaluated_get(depsgraph)
    mesh = obj_eval.to_mesh()
    try:
        return read(obj, mesh)
    finally:
        obj_eval.to_mesh_clear()


def evaluated_counts(obj, depsgraph=None) -> tuple[int, int]:
    """Triangle counts after the object's modifier stack."""
    return evaluated(obj, triangle_counts, depsgraph)


def remove_decimate(obj) -> None:
    """Remove the decimate modifiers this module added (any kind) and their derived groups."""
    for name in (STYLE_MODIFIER, PLAIN_MODIFIER, *SPLIT_MODIFIERS):
        mod = obj.modifiers.get(name)
        if mod is not None:
            obj.modifiers.remove(mod)
    for name in (SOFT_GROUP, *SPLIT_GROUPS):
        group = obj.vertex_groups.get(name)
        if group is not None:
            obj.vertex_groups.remove(group)


def _soft_group(obj):
    """(Re)write the capped copy of the style weights that soft protection drives."""
    return set_group_weights(obj, SOFT_GROUP, np.minimum(vertex_weights(obj), SOFT_CAP)).name


def _set_modifier(obj, ratio, strength, style_preserving, hard=True):
    name, other = ((STYLE_MODIFIER, PLAIN_MODIFIER) if style_preserving
                   else (PLAIN_MODIFIER, STYLE_MODIFIER))
    if obj.modifiers.get(other) is not None:
        obj.modifiers.remove(obj.modifiers[other])
    mod = obj.modifiers.get(name) or obj.modifiers.new(name, "DECIMATE")
    mod.decimate_type = "COLLAPSE"
    mod.ratio = float(ratio)
    if style_preserving:
        mod.vertex_group = GROUP if hard else _soft_group(obj)
        mod.invert_vertex_group = True
        mod.vertex_group_factor = float(strength)
    else:
        mod.vertex_group = ""
        mod.invert_vertex_group = False
    return mod


def _apply(obj, mod_name):
    """Apply one modifier (only ours, not the rest of the stack); shared meshes become single
    user so the other objects keep their geometry."""
    with bpy.context.temp_override(object=obj, active_object=obj, selected_objects=[obj]):
        bpy.ops.object.modifier_apply(modifier=mod_name, single_user=True)


def add_decimate(obj, ratio: float, strength: float = 1.0, style_preserving: bool = True,
                 apply: bool = False, depsgraph=None, hard: bool = True) -> dict:
    """Add (or update) a COLLAPSE Decimate modifier on `obj` and report what it reached.

    style_preserving=True drives the modifier with the `style_weight` group (inverted, factor =
    strength); False is the plain twin for comparison. hard=False protects softly (see above). Returns triangle counts before/after,
    overall and inside style regions, and the requested target. With apply=True the modifier is
    applied to the mesh.
    """
    if obj is None or obj.type != "MESH":
        raise ValueError(f"'{getattr(obj, 'name', obj)}' is not a mesh object")
    if style_preserving and obj.vertex_groups.get(GROUP) is None:
        raise ValueError(f"'{obj.name}' has no '{GROUP}' vertex group: analyse it first")
    before, style_before = triangle_counts(obj)
    mod = _set_modifier(obj, ratio, strength, style_preserving, hard)
    after, style_after = evaluated_counts(obj, depsgraph)
    name = mod.name
    if apply:
        _apply(obj, name)
    return {
        "object": obj.name, "modifier": name, "style_preserving": style_preserving,
        "hard": bool(hard) if style_preserving else None,
        "ratio": float(ratio), "strength": float(strength) if style_preserving else 0.0,
        "requested_triangles": int(round(ratio * before)),
        "triangles_before": before, "style_triangles_before": style_before,
        "triangles": after, "style_triangles": style_after, "applied": bool(apply),
    }


def add_split_decimate(obj, ratio: float, plain_keep: float | None = None, apply: bool = False,
                       depsgraph=None) -> dict:
    """Decimate the plain part to `plain_keep` of its triangles (default: a third of `ratio`),
    then the style part to whatever reaches `ratio` overall (see the module docstring). Two
    stacked COLLAPSE modifiers; returns the same counts as `add_decimate`."""
    if obj is None or obj.type != "MESH":
        raise ValueError(f"'{getattr(obj, 'name', obj)}' is not a mesh object")
    if obj.vertex_groups.get(GROUP) is None:
        raise ValueError(f"'{obj.name}' has no '{GROUP}' vertex group: analyse it first")
    remove_decimate(obj)
    before, style_before = triangle_counts(obj)
    if before == 0:
        raise ValueError(f"'{obj.name}' has no faces")
    mesh = obj.data
    tris = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    tris = tris.reshape(-1, 3)
    weights = vertex_weights(obj)
    style_vertex = np.zeros(len(mesh.vertices), bool)
    style_vertex[tris[weights[tris].mean(axis=1) > THRESHOLD].ravel()] = True
    # weight 0 freezes a vertex, 1 leaves plain quadric decimation (the border stays put)
    plain_group = set_group_weights(obj, SPLIT_GROUPS[0], (~style_vertex).astype(np.float32)).name
    style_group = set_group_weights(obj, SPLIT_GROUPS[1], style_vertex.astype(np.float32)).name
    keep = ratio / 3.0 if plain_keep is None else float(plain_keep)
    target = int(round(ratio * before))
    first = obj.modifiers.new(SPLIT_MODIFIERS[0], "DECIMATE")
    first.ratio = min(1.0, (style_before + keep * (before - style_before)) / before)
    first.vertex_group = plain_group
    after_plain, _ = evaluated_counts(obj, depsgraph)
    second = obj.modifiers.new(SPLIT_MODIFIERS[1], "DECIMATE")
    second.ratio = min(1.0, target / max(after_plain, 1))
    second.vertex_group = style_group
    after, style_after = evaluated_counts(obj, depsgraph)
    if apply:
        for name in SPLIT_MODIFIERS:
            _apply(obj, name)
    return {
        "object": obj.name, "modifier": SPLIT_MODIFIERS[1], "style_preserving": True,
        "hard": None, "ratio": float(ratio), "strength": 0.0, "plain_keep": keep,
        "requested_triangles": target, "triangles_before": before,
        "style_triangles_before": style_before, "triangles": after, "style_triangles": style_after,
        "applied": bool(apply),
    }


def match_plain_to(obj, target_triangles: int, apply: bool = False, depsgraph=None,
                   max_steps: int = 24) -> dict:
    """Plain decimation of `obj` tuned (bisection on ratio) to reach `target_triangles`, e.g. the
    count the style-preserving modifier reached, for a comparison at equal triangle budget."""
    before, _ = triangle_counts(obj)
    if before == 0:
        raise ValueError(f"'{obj.name}' has no faces")
    lo, hi = 0.0, 1.0
    ratio = min(1.0, max(0.0, target_triangles / before))
    best = None
    for _ in range(max_steps):
        res = add_decimate(obj, ratio, style_preserving=False, depsgraph=depsgraph)
        gap = res["triangles"] - target_triangles
        if best is None or abs(gap) < abs(best["triangles"] - target_triangles):
            best = res
        if gap == 0:
            break
        if gap > 0:
            hi = ratio
        else:
            lo = ratio
        ratio = 0.5 * (lo + hi)
        if hi - lo < 1e-7:
            break
    res = add_decimate(obj, best["ratio"], style_preserving=False, apply=apply,
                       depsgraph=depsgraph)
    res["target_triangles"] = int(target_triangles)
    return res
