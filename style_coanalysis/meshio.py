"""Plain-Python OBJ and ground-truth files, so the core can read and write shapes without Blender.

OBJ is the lowest common denominator of furniture collections; the reader accepts what such files
really hold (vertex colours after xyz, v/vt/vn face forms, negative indices, polygons) and refuses
anything else with an InputError that names the file and line.
"""
from __future__ import annotations

import os

import numpy as np

from .meshes import InputError, Mesh, triangulate


def write_obj(mesh: Mesh, path) -> None:
    """Triangles, 1-based indices, 6 significant digits past the point (sub-micron at 1 m)."""
    path = os.fspath(path)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(f"# {mesh.name}\no {mesh.name}\n")
        np.savetxt(fh, mesh.vertices, fmt="v %.6f %.6f %.6f")
        np.savetxt(fh, mesh.faces + 1, fmt="f %d %d %d")


def _index(token: str, n_vertices: int, path: str, lineno: int) -> int:
    """OBJ index (1-based, or negative = relative to the vertices read so far) -> 0-based."""
    head = token.split("/", 1)[0]
    try:
        k = int(head)
    except ValueError:
        raise InputError(f"{path}:{lineno}: bad face index '{token}'") from None
    if k == 0:
        raise InputError(f"{path}:{lineno}: face index 0 (OBJ indices start at 1)")
    idx = k - 1 if k > 0 else n_vertices + k
    if idx < 0:
        raise InputError(f"{path}:{lineno}: face index {k} points before the first vertex")
    return idx


def read_obj(path, name: str | None = None) -> Mesh:
    """All objects/groups of the file as one mesh named after the file stem."""
    path = os.fspath(path)
    verts, polys = [], []
    try:
        with open(path, "r", encoding="utf-8", errors="replace") as fh:
            for lineno, line in enumerate(fh, 1):
                parts = line.split()
                if not parts or parts[0].startswith("#"):
                    continue
                tag = parts[0]
                if tag == "v":
                    if len(parts) < 4:
                        raise InputError(f"{path}:{lineno}: vertex needs 3 coordinates")
                    try:
                        verts.append([float(x) for x in parts[1:4]])  # colours ignored
                    except ValueError:
                        raise InputError(f"{path}:{lineno}: bad vertex '{line.strip()}'") from None
                elif tag == "f":
                    if len(parts) < 4:
                        raise InputError(f"{path}:{lineno}: face needs at least 3 vertices")
                    polys.append([_index(t, len(verts), path, lineno) for t in parts[1:]])
                elif tag in ("vt", "vn", "vp", "o", "g", "s", "usemtl", "mtllib", "l", "p"):
                    continue
                elif not tag.isascii() or not tag.isalpha():
                    raise InputError(f"{path}:{lineno}: not an OBJ file (unexpected '{tag[:20]}')")
    except (OSError, UnicodeError) as exc:
        raise InputError(f"{path}: cannot read ({exc})") from None
    if not polys:
        raise InputError(f"{path}: no faces")
    faces = triangulate(polys)
    if faces.max() >= len(verts):
        raise InputError(f"{path}: a face indexes vertex {faces.max() + 1} but there are {len(verts)}")
    stem = os.path.splitext(os.path.basename(path))[0]
    return Mesh(name or stem, np.asarray(verts, np.float32), faces, source=path)


def write_truth(mesh: Mesh, path) -> None:
    """Ground truth beside the mesh (style, category, decorative-face mask) as .npz."""
    t = mesh.truth
    mask = np.asarray(t.get("face_mask", np.zeros(0, bool)), bool)
    np.savez_compressed(os.fspath(path), name=np.array(mesh.name), style=np.array(t.get("style", "")),
                        category=np.array(t.get("category", "")), face_mask=mask)


def read_truth(path) -> dict:
    """The dict `write_truth` stored (keys style, category, face_mask)."""
    path = os.fspath(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            return {"style": str(z["style"]), "category": str(z["category"]),
                    "face_mask": z["face_mask"].astype(bool)}
    except (OSError, KeyError, ValueError) as exc:
        raise InputError(f"{path}: not a truth file ({exc})") from None
