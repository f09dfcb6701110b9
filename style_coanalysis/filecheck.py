"""Vertex coordinates read straight from mesh files, before Blender's importers see them.

Blender's OBJ, STL, PLY and glTF importers turn `nan` and `inf` into 0 without a word, so a damaged
file would be analysed as a different shape. `bad_coordinates(path)` reads the coordinates
itself (text and binary OBJ/STL/PLY, glTF/GLB position accessors) and counts the vertices with
NaN, infinite or absurd (beyond `COORDINATE_LIMIT`) values. Files it cannot parse are left to
the importer, which reports them. Pure Python and numpy: no bpy.
"""
from __future__ import annotations

import base64
import json
import os
import re
import struct

import numpy as np

from .options import COORDINATE_LIMIT


def _count_bad(values: np.ndarray) -> int:
    """Rows of an (N, 3) array with a NaN, infinite or absurd value."""
    v = np.asarray(values, np.float64).reshape(-1, 3)
    with np.errstate(invalid="ignore"):
        return int((~(np.abs(v) <= COORDINATE_LIMIT).all(axis=1)).sum())


def _floats(tokens) -> list[float]:
    out = []
    for t in tokens:
        try:
            out.append(float(t))
        except ValueError:
            out.append(float("nan"))      # unreadable is as bad as NaN: the importer reads 0
    return out


# Anything in a text file that could be a bad coordinate: nan, inf, an exponent of 31 or more,
# or 31 digits in a row. Files without any are passed without parsing them line by line.
_SUSPECT = re.compile(rb"(?i)nan|inf|e\+?0*(3[1-9]|[4-9]\d|\d{3,})|\d{31}")


def _text_rows(data: bytes, tag: bytes) -> np.ndarray:
    """xyz of every line starting with `tag` (b'v' for OBJ, b'vertex' for ASCII STL)."""
    if not _SUSPECT.search(data):
        return np.zeros((0, 3))
    rows = []
    for line in data.splitlines():
        parts = line.split()
        if len(parts) >= 4 and parts[0] == tag:
            rows.append(_floats(p.decode("ascii", "replace") for p in parts[1:4]))
    return np.array(rows, np.float64).reshape(-1, 3)


def _obj(data: bytes) -> np.ndarray:
    return _text_rows(data, b"v")


def _stl(data: bytes) -> np.ndarray:
    if len(data) >= 84:
        n = struct.unpack_from("<I", data, 80)[0]
        if 84 + 50 * n == len(data):                       # binary STL
            tri = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)),
                                                      ("a", "<u2")]), count=n, offset=84)
            return tri["v"].reshape(-1, 3)
    return _text_rows(data, b"vertex")


_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
              "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
              "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
              "float64": "f8"}


def _ply(data: bytes) -> np.ndarray | None:
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        return None
    body = data[data.index(b"\n", end) + 1:]
    header = data[:end].decode("ascii", "replace").splitlines()
    fmt, elements = None, []
    for line in header:
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "format":
            fmt = parts[1]
        elif parts[0] == "element":
            elements.append((parts[1], int(parts[2]), []))
        elif parts[0] == "property" and elements:
            elements[-1][2].append(parts[1:])
    if not elements or elements[0][0] != "vertex":
        return None                                         # unusual layout: leave it
    _, n, props = elements[0]
    names = [p[-1] for p in props]
    if not {"x", "y", "z"} <= set(names) or any(p[0] == "list" for p in props):
        return None
    cols = [names.index(a) for a in "xyz"]
    if fmt == "ascii":
        rows = []
        for line in body.splitlines()[:n]:
            cells = line.split()
            rows.append(_floats(cells[c].decode("ascii", "replace") if c < len(cells) else "x"
                                for c in cols))
        return np.array(rows, np.float64).reshape(-1, 3)
    order = "<" if fmt == "binary_little_endian" else ">"
    try:
        dtype = np.dtype([(f"p{k}", order + _PLY_TYPES[p[0]]) for k, p in enumerate(props)])
        vert = np.frombuffer(body, dtype=dtype, count=n)
    except (KeyError, ValueError, TypeError):
        return None
    return np.stack([vert[f"p{c}"].astype(np.float64) for c in cols], axis=1)


def _gltf(path: str, data: bytes) -> np.ndarray | None:
    """POSITION accessors of every primitive (float, not sparse) of a .gltf or .glb."""
    bin_chunk = None
    if data[:4] == b"glTF":
        length = struct.unpack_from("<I", data, 12)[0]
        doc = json.loads(data[20:20 + length])
        offset = 20 + length
        if offset + 8 <= len(data):
            blen = struct.unpack_from("<I", data, offset)[0]
            bin_chunk = data[offset + 8:offset + 8 + blen]
    else:
        doc = json.loads(data.decode("utf-8"))
    buffers = []
    for k, b in enumerate(doc.get("buffers", [])):
        uri = b.get("uri")
        if uri is None:
            buffers.append(bin_chunk if k == 0 else None)
        elif uri.startswith("data:"):
            buffers.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            p = os.path.join(os.path.dirname(path), uri)
            buffers.append(open(p, "rb").read() if os.path.isfile(p) else None)
    out = []
    for mesh in doc.get("meshes", []):
        for prim in mesh.get("primitives", []):
            a = prim.get("attributes", {}).get("POSITION")
            if a is None:
                continue
            acc = doc["accessors"][a]
            if acc.get("componentType") != 5126 or "bufferView" not in acc:
                continue
            view = doc["bufferViews"][acc["bufferView"]]
            buf = buffers[view["buffer"]]
            if buf is None:
                continue
            start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
            stride = view.get("byteStride", 12)
            count = acc["count"]
            raw = np.frombuffer(buf, np.uint8, count=max(0, (count - 1) * stride + 12), offset=start)
            idx = (np.arange(count)[:, None] * stride + np.arange(12)[None, :]).ravel()
            out.append(raw[idx].view("<f4").reshape(-1, 3))
    return np.concatenate(out) if out else np.zeros((0, 3))


def bad_coordinates(path) -> int:
    """How many vertices of the mesh file have NaN, infinite or absurd coordinates (0 when the
    file cannot be parsed here: the importer then has the last word)."""
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    try:
        with open(path, "rb") as fh:
            data = fh.read()
        if ext == ".obj":
            xyz = _obj(data)
        elif ext == ".stl":
            xyz = _stl(data)
        elif ext == ".ply":
            xyz = _ply(data)
        elif ext in (".gltf", ".glb"):
            xyz = _gltf(path, data)
        else:
            return 0
    except (OSError, ValueError, KeyError, IndexError, TypeError, struct.error,
            UnicodeDecodeError, re.error):
        return 0
    return 0 if xyz is None else _count_bad(xyz)
