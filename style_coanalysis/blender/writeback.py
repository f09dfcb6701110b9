"""Write an analysis result into the scene, and take it out again exactly.

What `write_results` puts on every analysed mesh object:
- vertex group `style_weight`: the per-vertex style weights (1 = style region);
- material "Style Highlight" (one shared datablock) in a slot appended after the mesh's own slots,
  assigned to faces whose mean vertex weight > 0.5. The mesh's own materials are not touched; the
  faces' original material indices are kept in the int face attribute `style_orig_material_index`
  so that `clear_results` (and every re-run, which clears first) restores them exactly;
- custom properties `style_cluster`, `style_label` ('' when none), `style_label_given`,
  `style_confidence`, `style_best_view`, `style_best_view_matrix` (16 floats, row-major camera
  world matrix);
- links (never moves) the object into "<prefix> Cluster <id>" under "<prefix> Clusters".

Meshes shared by several objects: vertex groups, material slots and face attributes live on the mesh
in Blender, so every user of a shared mesh sees the same style data. Such a mesh is written once,
with the mean of the weights computed for the analysed objects that use it; custom properties and
collection links are per object. Users of the mesh outside the analysis see the style data too
(making single-user copies would silently change the scene; we don't).

Nothing here runs the analysis; the operator calls `write_results` once, at the end of a run, so a
cancelled or failed run leaves the scene as it was.
"""
from __future__ import annotations

from collections import defaultdict

import bpy
import numpy as np

GROUP = "style_weight"
SOFT_GROUP = "style_weight_soft"        # capped copy written by decimate.py for soft protection
HIGHLIGHT = "Style Highlight"
ORIG_INDEX_ATTR = "style_orig_material_index"
SLOTS_KEY = "style_slots_before"        # mesh: number of material slots before the write
SHOWN_KEY = "style_highlight_shown"     # mesh: highlight material currently assigned to faces
HAD_INDEX_KEY = "style_had_material_index"  # mesh: a 'material_index' attribute existed before
MARK = "style_coanalysis"               # custom property on datablocks this module created
THRESHOLD = 0.5
ORANGE = (1.0, 0.45, 0.05, 1.0)
OBJECT_KEYS = ("style_cluster", "style_label", "style_label_given", "style_confidence",
               "style_best_view", "style_best_view_matrix")
# what Identify Style from Drawings writes (operators/uses.py): per object, and its scene list
IDENTIFIED_KEYS = ("style_identified", "style_identified_votes")
IDENTIFIED_GROUP = "style_identified_weight"
IDENTIFIED_SCENE_KEY = "style_identified"


class WritebackError(ValueError):
    """The result does not fit the scene (an object is missing or its mesh changed)."""


# --------------------------------------------------------------------------------------------
# helpers

def vertex_weights(obj_or_mesh_owner, mesh=None, group=GROUP) -> np.ndarray:
    """Per-vertex weights of `group` (0 where a vertex is not in it). `mesh` defaults to the
    object's own mesh; pass an evaluated mesh to read weights that survived modifiers."""
    mesh = mesh if mesh is not None else obj_or_mesh_owner.data
    weights = np.zeros(len(mesh.vertices), dtype=np.float32)
    names = [g.name for g in obj_or_mesh_owner.vertex_groups]
    if group not in names:
        return weights
    gi = names.index(group)
    for v in mesh.vertices:
        for g in v.groups:
            if g.group == gi:
                weights[v.index] = g.weight
                break
    return weights


def set_group_weights(obj, name: str, weights: np.ndarray):
    """Create or overwrite vertex group `name` with one weight per vertex (all vertices)."""
    group = obj.vertex_groups.get(name) or obj.vertex_groups.new(name=name)
    # One add() call per distinct weight value: binary masks cost two calls, not one per vertex.
    values, inverse = np.unique(np.asarray(weights, np.float32), return_inverse=True)
    order = np.argsort(inverse, kind="stable")
    bounds = np.searchsorted(inverse[order], np.arange(len(values) + 1))
    for k, value in enumerate(values):
        group.add(order[bounds[k]:bounds[k + 1]].tolist(), float(value), "REPLACE")
    return group


def face_mean(mesh, per_vertex: np.ndarray) -> np.ndarray:
    """Mean of a per-vertex value over each polygon's corners."""
    n = len(mesh.polygons)
    if n == 0:
        return np.zeros(0, dtype=np.float64)
    starts = np.empty(n, dtype=np.int32)
    totals = np.empty(n, dtype=np.int32)
    mesh.polygons.foreach_get("loop_start", starts)
    mesh.polygons.foreach_get("loop_total", totals)
    corners = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", corners)
    sums = np.add.reduceat(per_vertex.astype(np.float64)[corners], starts)
    return sums / totals


def material_indices(mesh) -> np.ndarray:
    idx = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("material_index", idx)
    return idx


def highlight_material(create=True):
    """The one shared highlight material (found by its mark, so a rename does not duplicate it)."""
    for mat in bpy.data.materials:
        if mat.get(MARK) == "highlight":
            return mat
    if not create:
        return None
    mat = bpy.data.materials.new(HIGHLIGHT)
    mat[MARK] = "highlight"
    mat.diffuse_color = ORANGE                      # solid viewport colour
    # New materials come with a node tree in Blender 5 (no deprecated use_nodes setter needed).
    tree = mat.node_tree
    bsdf = next((n for n in tree.nodes if n.type == "BSDF_PRINCIPLED"), None) if tree else None
    if bsdf is not None:
        bsdf.inputs["Base Color"].default_value = ORANGE
        bsdf.inputs["Emission Color"].default_value = ORANGE
        bsdf.inputs["Emission Strength"].default_value = 1.0
    return mat


def _is_ours(id_block, kind):
    return id_block.get(MARK) == kind


# --------------------------------------------------------------------------------------------
# write

def _check(scene, result):
    """Refuse before any change: every shape must be a mesh object of this scene whose vertex
    count matches its weights, and whose mesh can be edited."""
    problems = []
    for shape in result.shapes:
        obj = scene.objects.get(shape.name)
        if obj is None:
            problems.append(f"'{shape.name}' is no longer in scene '{scene.name}'")
            continue
        if obj.type != "MESH":
            problems.append(f"'{shape.name}' is not a mesh")
            continue
        if obj.data.library is not None or obj.library is not None:
            problems.append(f"'{shape.name}' is linked from a library and cannot be changed")
            continue
        n = len(obj.data.vertices)
        w = np.asarray(shape.vertex_weights).reshape(-1)
        if len(w) != n:
            problems.append(f"'{shape.name}' has {n} vertices but the analysis gave {len(w)} "
                            "weights (mesh edited since, or modifiers change its vertex count)")
        elif not np.all(np.isfinite(w)):
            problems.append(f"'{shape.name}' received non-finite style weights")
    if problems:
        raise WritebackError("; ".join(problems))


def _write_mesh(obj, weights: np.ndarray, material) -> int:
    """Vertex group, highlight slot and face attribute on one (cleared) mesh; returns the number
    of highlighted faces."""
    mesh = obj.data
    weights = np.clip(weights.astype(np.float32), 0.0, 1.0)

    set_group_weights(obj, GROUP, weights)

    original = material_indices(mesh)
    slots_before = len(mesh.materials)
    # Faces may index past the last slot; pad with empty slots so no face ever lands on ours.
    needed = max(slots_before, int(original.max()) + 1 if len(original) else 0)
    while len(mesh.materials) < needed:
        mesh.materials.append(None)
    mesh.materials.append(material)
    highlight_index = needed

    attr = mesh.attributes.new(ORIG_INDEX_ATTR, "INT", "FACE")
    attr.data.foreach_set("value", original)
    mesh[SLOTS_KEY] = slots_before
    mesh[SHOWN_KEY] = True
    # Meshes whose faces all use slot 0 have no 'material_index' attribute; writing indices
    # creates it, so remember to drop it again on clear.
    mesh[HAD_INDEX_KEY] = "material_index" in mesh.attributes

    styled = face_mean(mesh, weights) > THRESHOLD
    mesh.polygons.foreach_set("material_index", np.where(styled, highlight_index, original)
                              .astype(np.int32))
    mesh.update()
    return int(styled.sum())


def write_results(scene, result, collection_prefix: str = "Style", progress=None) -> dict:
    """Replace whatever an earlier run wrote in `scene` with `result` (a JobResult).

    `progress(stage, done, total)`, if given, is called per mesh written (large meshes take
    seconds each).

    Raises WritebackError naming the objects before changing anything if the result does not fit
    the scene. Returns a summary: objects written, meshes written, shared meshes, highlighted
    faces per object.
    """
    _check(scene, result)
    clear_results(scene)

    material = highlight_material()
    by_mesh = defaultdict(list)
    for shape in result.shapes:
        by_mesh[scene.objects[shape.name].data.name].append(shape)

    highlighted, shared = {}, []
    for k, (mesh_name, shapes) in enumerate(by_mesh.items()):
        if progress is not None:
            progress("write", k, len(by_mesh))
        if len(shapes) > 1:
            shared.append(mesh_name)
        weights = np.mean([np.asarray(s.vertex_weights, dtype=np.float32).reshape(-1)
                           for s in shapes], axis=0)
        count = _write_mesh(scene.objects[shapes[0].name], weights, material)
        for s in shapes:
            highlighted[s.name] = count

    for shape in result.shapes:
        obj = scene.objects[shape.name]
        obj["style_cluster"] = int(shape.cluster)
        obj["style_label"] = shape.label or ""
        obj["style_label_given"] = bool(shape.label_given)
        obj["style_confidence"] = float(shape.confidence)
        obj["style_best_view"] = int(shape.best_view)
        matrix = np.asarray(shape.best_view_matrix, dtype=np.float64).reshape(-1)
        if matrix.size == 16:
            obj["style_best_view_matrix"] = [float(x) for x in matrix]

    parent = bpy.data.collections.new(f"{collection_prefix} Clusters")
    parent[MARK] = "clusters"
    scene.collection.children.link(parent)
    members = defaultdict(list)
    for shape in result.shapes:
        members[int(shape.cluster)].append(shape.name)
    cluster_ids = sorted({int(c["id"]) for c in result.clusters} | set(members))
    for cid in cluster_ids:
        col = bpy.data.collections.new(f"{collection_prefix} Cluster {cid}")
        col[MARK] = "cluster"
        col["style_cluster"] = cid
        parent.children.link(col)
        for name in members.get(cid, ()):
            col.objects.link(scene.objects[name])

    settings = getattr(scene, "style_coanalysis", None)
    if settings is not None:
        info = {int(c["id"]): c for c in result.clusters}
        for cid in cluster_ids:
            item = settings.clusters.add()
            item.cluster_id = cid
            item.size = len(members.get(cid, ()))
            item.label = (info.get(cid, {}).get("label") or "")
        skipped = f", {len(result.skipped)} skipped" if result.skipped else ""
        from ..report import firmness_label            # PIL: only once a run ends
        firm = firmness_label(result.report)
        settings.last_report = (f"{len(result.shapes)} shapes in {len(cluster_ids)} clusters"
                                f"{skipped}{', ' + firm if firm else ''}")
    if progress is not None:
        progress("write", len(by_mesh), len(by_mesh))
    return {"objects": len(result.shapes), "meshes": len(by_mesh), "shared_meshes": shared,
            "highlighted_faces": highlighted, "clusters": len(cluster_ids)}


# --------------------------------------------------------------------------------------------
# clear and display

def _clear_mesh(obj):
    mesh = obj.data
    if SLOTS_KEY not in mesh:
        return
    slots_before = int(mesh[SLOTS_KEY])
    attr = mesh.attributes.get(ORIG_INDEX_ATTR)
    original = None
    if attr is not None and len(attr.data) == len(mesh.polygons):
        original = np.empty(len(mesh.polygons), dtype=np.int32)
        attr.data.foreach_get("value", original)
    while len(mesh.materials) > slots_before:
        mesh.materials.pop(index=len(mesh.materials) - 1)
    if original is not None:
        mesh.polygons.foreach_set("material_index", original)
    if attr is not None:
        mesh.attributes.remove(attr)
    index_attr = mesh.attributes.get("material_index")
    if (not mesh.get(HAD_INDEX_KEY, True) and index_attr is not None
            and not material_indices(mesh).any()):
        mesh.attributes.remove(index_attr)
    for key in (SLOTS_KEY, SHOWN_KEY, HAD_INDEX_KEY):
        if key in mesh:
            del mesh[key]
    for name in (GROUP, SOFT_GROUP):
        group = obj.vertex_groups.get(name)
        if group is not None:
            obj.vertex_groups.remove(group)
    mesh.update()


def clear_results(scene) -> int:
    """Remove everything `write_results` put in `scene`; returns the number of objects cleared.
    Material indices come back from the stored attribute, so the meshes are as before."""
    cleared = 0
    done_meshes = set()
    for obj in scene.objects:
        had = any(k in obj for k in OBJECT_KEYS)
        for key in OBJECT_KEYS:
            if key in obj:
                del obj[key]
        if obj.type == "MESH" and obj.data.name not in done_meshes and SLOTS_KEY in obj.data:
            done_meshes.add(obj.data.name)
            _clear_mesh(obj)
            had = True
        cleared += had

    for parent in list(scene.collection.children):
        if _is_ours(parent, "clusters"):
            for child in list(parent.children):
                if _is_ours(child, "cluster"):
                    bpy.data.collections.remove(child)
            bpy.data.collections.remove(parent)

    material = highlight_material(create=False)
    if material is not None and material.users == 0:
        bpy.data.materials.remove(material)

    settings = getattr(scene, "style_coanalysis", None)
    if settings is not None:
        settings.clusters.clear()
        settings.active_cluster_index = 0
        settings.last_report = ""
    return cleared


def has_identified(obj) -> bool:
    """Whether Identify Style from Drawings wrote on `obj`."""
    return any(k in obj for k in IDENTIFIED_KEYS) or (
        obj.type == "MESH" and obj.vertex_groups.get(IDENTIFIED_GROUP) is not None)


def clear_identified(scene) -> int:
    """Remove what Identify Style from Drawings wrote (its properties and vertex group, and the
    scene's list); returns the number of objects cleared. Separate from `clear_results`, which
    every analysis run calls first: a new analysis does not erase an identification."""
    cleared = 0
    for obj in scene.objects:
        if not has_identified(obj):
            continue
        for key in IDENTIFIED_KEYS:
            if key in obj:
                del obj[key]
        group = obj.vertex_groups.get(IDENTIFIED_GROUP) if obj.type == "MESH" else None
        if group is not None:
            obj.vertex_groups.remove(group)
        cleared += 1
    if IDENTIFIED_SCENE_KEY in scene:
        del scene[IDENTIFIED_SCENE_KEY]
    return cleared


def set_highlight_shown(obj, shown: bool) -> bool:
    """Show or hide the highlight material on `obj`'s style faces (the slot stays, so this is
    cheap and exact both ways). Returns False when the object carries no results."""
    mesh = obj.data
    if SLOTS_KEY not in mesh or ORIG_INDEX_ATTR not in mesh.attributes:
        return False
    original = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.attributes[ORIG_INDEX_ATTR].data.foreach_get("value", original)
    if shown:
        styled = face_mean(mesh, vertex_weights(obj)) > THRESHOLD
        highlight_index = len(mesh.materials) - 1
        original = np.where(styled, highlight_index, original).astype(np.int32)
    mesh.polygons.foreach_set("material_index", original)
    mesh[SHOWN_KEY] = bool(shown)
    mesh.update()
    return True


def has_results(obj) -> bool:
    return obj is not None and "style_cluster" in obj
