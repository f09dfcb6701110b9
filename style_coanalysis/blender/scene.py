"""Blender <-> `Mesh`: read objects, .blend files and mesh files into plain arrays, write shapes back.

The one place that turns Blender data into what the pure core speaks. Vertex order is Blender's
own (evaluated) vertex order, so per-vertex results map back to the object 1:1. Input files are
only read: importers load into the current session and the imported objects are removed again.
"""
from __future__ import annotations

import os

import bpy
import numpy as np

from ..meshes import InputError, Mesh

TRUTH_ATTRIBUTE = "style_truth"        # boolean face attribute: True on decorative faces
MESH_EXTENSIONS = (".obj", ".ply", ".stl", ".gltf", ".glb")


def mesh_from_object(obj, depsgraph) -> Mesh:
    """Evaluated (modifiers applied) triangles of `obj` in world orientation and scale, relative
    to the object's location (`Mesh.origin`): an object's own coordinates keep their float32
    bits wherever it sits in the scene."""
    ev = obj.evaluated_get(depsgraph)
    me = ev.to_mesh()
    try:
        me.calc_loop_triangles()
        n = len(me.vertices)
        co = np.empty(n * 3, np.float64)
        me.vertices.foreach_get("co", co)
        co = co.reshape(n, 3)
        mw = np.array(ev.matrix_world, dtype=np.float64)
        placed = co @ mw[:3, :3].T
        m = len(me.loop_triangles)
        tris = np.empty(m * 3, np.int32)
        me.loop_triangles.foreach_get("vertices", tris)
        poly = np.empty(m, np.int32)
        me.loop_triangles.foreach_get("polygon_index", poly)
        truth = {}
        for key in ("style", "category"):
            if key in obj.keys():
                truth[key] = str(obj[key])
        attr = me.attributes.get(TRUTH_ATTRIBUTE)
        if attr is not None and attr.domain == "FACE" and attr.data_type == "BOOLEAN":
            per_poly = np.empty(len(me.polygons), bool)
            attr.data.foreach_get("value", per_poly)
            truth["face_mask"] = per_poly[poly]
    finally:
        ev.to_mesh_clear()
    return Mesh(obj.name, placed.astype(np.float32), tris.reshape(-1, 3), source=obj.name,
                truth=truth, origin=mw[:3, 3])


def meshes_from_blend(path, collection: str | None = None) -> list[Mesh]:
    """Mesh objects of a .blend (or of one of its collections), sorted by name.

    Opens the file as the current session (the file itself is never written)."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise InputError(f"{path}: no such .blend file")
    try:
        bpy.ops.wm.open_mainfile(filepath=path, load_ui=False)
    except RuntimeError as exc:
        raise InputError(f"{path}: cannot open as a .blend file ({exc})") from None
    if collection:
        coll = bpy.data.collections.get(collection)
        if coll is None:
            known = ", ".join(sorted(c.name for c in bpy.data.collections)) or "none"
            raise InputError(f"{path}: no collection '{collection}' (collections: {known})")
        objects = list(coll.all_objects)
        where = f"collection '{collection}' of {path}"
    else:
        objects = list(bpy.context.scene.objects)
        where = path
    names = sorted(o.name for o in objects if o.type == "MESH")
    if not names:
        raise InputError(f"{where}: no mesh objects")
    depsgraph = bpy.context.evaluated_depsgraph_get()
    return [mesh_from_object(bpy.data.objects[n], depsgraph) for n in names]


def _import_one(path: str) -> None:
    ext = os.path.splitext(path)[1].lower()
    # OBJ/PLY/STL: take coordinates as they are (Z up); the pipeline's --up flag handles Y-up
    # assets, exactly as the plain-Python OBJ reader does. glTF is Y-up by specification and
    # Blender's importer converts it.
    if ext == ".obj":
        bpy.ops.wm.obj_import(filepath=path, forward_axis="Y", up_axis="Z")
    elif ext == ".ply":
        bpy.ops.wm.ply_import(filepath=path, forward_axis="Y", up_axis="Z")
    elif ext == ".stl":
        bpy.ops.wm.stl_import(filepath=path, forward_axis="Y", up_axis="Z")
    else:
        bpy.ops.import_scene.gltf(filepath=path)


def _remove_objects(names) -> None:
    for n in names:
        obj = bpy.data.objects.get(n)
        if obj is None:
            continue
        data = obj.data if obj.type == "MESH" else None
        bpy.data.objects.remove(obj)
        if data is not None and data.users == 0:
            bpy.data.meshes.remove(data)


FORMAT_NAMES = {".obj": "OBJ", ".ply": "PLY", ".stl": "STL", ".gltf": "glTF", ".glb": "glTF"}


def import_mesh_file(path) -> Mesh:
    """One shape from one file (all its mesh objects joined), named by the file stem.

    One rule for every format: a file that is not a mesh of its type (the importer fails, or
    finds no mesh with a vertex in it) raises InputError naming the file, and so does a file
    with NaN, infinite or absurd coordinates, which Blender's importers would silently read as 0
    (`filecheck`). The importers' own output (pages of warnings on garbage) is kept off the
    terminal. A mesh with vertices but no faces is returned as it is: the job skips it.
    """
    from ..filecheck import bad_coordinates
    from ..options import COORDINATE_LIMIT
    from .render import quiet_fds
    path = os.fspath(path)
    stem = os.path.splitext(os.path.basename(path))[0]
    kind = FORMAT_NAMES.get(os.path.splitext(path)[1].lower(), "mesh")
    bad = bad_coordinates(path)
    if bad:
        raise InputError(f"{path}: '{stem}' has {bad} vertices with NaN, infinite or absurd "
                         f"(beyond {COORDINATE_LIMIT:g}) coordinates (Blender's importer would "
                         "read them as 0)")
    before = set(bpy.data.objects.keys())
    try:
        with quiet_fds():
            _import_one(path)
    except RuntimeError as exc:
        _remove_objects(set(bpy.data.objects.keys()) - before)
        lines = [ln.strip() for ln in str(exc).strip().splitlines() if ln.strip()]
        why = lines[0] if lines else "the importer failed"
        if why.startswith("Error: "):
            why = why[len("Error: "):]
        raise InputError(f"{path}: not a readable {kind} file ({why})") from None
    new = sorted(set(bpy.data.objects.keys()) - before)
    try:
        depsgraph = bpy.context.evaluated_depsgraph_get()
        parts = [mesh_from_object(bpy.data.objects[n], depsgraph) for n in new
                 if bpy.data.objects[n].type == "MESH"]
        if not any(len(p.vertices) for p in parts):
            raise InputError(f"{path}: not a readable {kind} file (no mesh in it)")
        with_faces = [p for p in parts if len(p.faces)]
        if not with_faces:
            # not an import failure: the shape exists but cannot be analysed; the job skips it
            # with a warning and lists it in the report
            return Mesh(stem, _joined(parts), np.zeros((0, 3), np.int32), source=path,
                        origin=parts[0].origin)
        parts = with_faces
        offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
        faces = np.concatenate([p.faces + o for p, o in zip(parts, offsets)])
    finally:
        _remove_objects(new)
    return Mesh(stem, _joined(parts), faces, source=path, origin=parts[0].origin)


def _joined(parts) -> np.ndarray:
    """The parts' vertices in one array, relative to the first part's origin."""
    return np.concatenate([p.vertices.astype(np.float64) + (p.origin - parts[0].origin)
                           for p in parts])


def import_mesh_files(folder) -> list[Mesh]:
    """Every OBJ/PLY/STL/glTF file of `folder` (not recursive), sorted by file name."""
    folder = os.fspath(folder)
    if not os.path.isdir(folder):
        raise InputError(f"{folder}: no such folder")
    files = sorted(f for f in os.listdir(folder) if f.lower().endswith(MESH_EXTENSIONS))
    if not files:
        raise InputError(f"{folder}: no mesh files ({', '.join(MESH_EXTENSIONS)})")
    stems = [os.path.splitext(f)[0] for f in files]
    dup = sorted({s for s in stems if stems.count(s) > 1})
    if dup:
        raise InputError(f"{folder}: several files share the name '{dup[0]}' (shapes are named by stem)")
    return [import_mesh_file(os.path.join(folder, f)) for f in files]


def objects_from_meshes(meshes, collection_name: str) -> list[str]:
    """One object per mesh, at the mesh's origin, in a (new or existing) collection of the
    current scene. Truth goes to custom properties 'style'/'category' and the boolean face
    attribute 'style_truth'. Returns the object names Blender gave (they differ from mesh names
    on clashes)."""
    coll = bpy.data.collections.get(collection_name)
    if coll is None:
        coll = bpy.data.collections.new(collection_name)
    if coll.name not in bpy.context.scene.collection.children:
        bpy.context.scene.collection.children.link(coll)
    names = []
    for m in meshes:
        me = bpy.data.meshes.new(m.name)
        nv, nf = len(m.vertices), len(m.faces)
        me.vertices.add(nv)
        me.vertices.foreach_set("co", m.vertices.astype(np.float32).ravel())
        me.loops.add(nf * 3)
        me.loops.foreach_set("vertex_index", m.faces.astype(np.int32).ravel())
        me.polygons.add(nf)
        me.polygons.foreach_set("loop_start", np.arange(0, nf * 3, 3, dtype=np.int32))
        me.update()
        obj = bpy.data.objects.new(m.name, me)
        obj.location = tuple(float(x) for x in m.origin)
        coll.objects.link(obj)
        for key in ("style", "category"):
            if key in m.truth:
                obj[key] = str(m.truth[key])
        mask = m.truth.get("face_mask")
        if mask is not None and len(mask) == nf:
            attr = me.attributes.new(TRUTH_ATTRIBUTE, "BOOLEAN", "FACE")
            attr.data.foreach_set("value", np.asarray(mask, bool))
        names.append(obj.name)
    return names


def empty_session() -> None:
    """An empty factory scene, keeping the preferences.

    Not `read_factory_settings`: inside Blender it also resets the preferences, which disables
    every extension, this one included, and removes their bundled wheels from disk mid-run
    (seen with bpy 4.5 and 5.0 and an installed zip)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True, load_ui=False)


GRID_SPACING = 3.0   # metres between shapes in a written .blend, so a person can look at them


def write_blend(meshes, path, collection_name: str) -> list[str]:
    """A fresh scene holding the meshes on a grid in one collection, saved to `path`; the
    object names. The `sample` command writes its .blend this way, the benchmark too."""
    import math
    empty_session()
    names = objects_from_meshes(meshes, collection_name)
    cols = max(1, math.ceil(math.sqrt(len(names))))
    for i, n in enumerate(names):
        bpy.data.objects[n].location = ((i % cols) * GRID_SPACING, (i // cols) * GRID_SPACING, 0.0)
    save_blend(path)
    return names


def save_blend(path) -> None:
    """Save the session to `path` as a copy (the session keeps its own file path)."""
    path = os.path.abspath(os.fspath(path))
    os.makedirs(os.path.dirname(path), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=path, copy=True, check_existing=False)
