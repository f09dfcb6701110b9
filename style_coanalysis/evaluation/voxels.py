"""Real furniture with expert style labels, as 30^3 binvox grids, turned into smooth closed meshes.

Why: the Hu et al. 2017 furniture set (see /work/shared/data/README.md) is the only real,
style-labelled collection we have. Its voxel faces are all 90-degree creases, which would turn
every line drawing into a staircase, so the grid is meshed with marching cubes and then
Taubin-smoothed (which, unlike Gaussian blurring of the grid, keeps one-voxel-thin legs).
"""
from __future__ import annotations

import csv
import os

import numpy as np
import scipy.sparse as sp
from skimage.measure import marching_cubes

from ..meshes import InputError, Mesh, up_to_z

DEFAULT_ROOT = "../shared/data/hu2017_vox"


def read_binvox(path) -> tuple[np.ndarray, np.ndarray, float]:
    """(occupancy bool (x, y, z), translate (3,), scale) of a binvox file.

    Measured on the Hu 2017 grids after this x, y, z reordering: the third axis (z) is up
    (table tops fill the highest z slices, chairs are tallest along z), not y as the data
    README says; `voxel_mesh(up=...)` lets a caller override that."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            if not fh.readline().startswith(b"#binvox"):
                raise InputError(f"{path}: not a binvox file")
            dims = translate = None
            scale = 1.0
            while True:
                line = fh.readline()
                if not line:
                    raise InputError(f"{path}: binvox header has no 'data' line")
                key, *vals = line.decode("ascii", "replace").split()
                if key == "dim":
                    dims = [int(v) for v in vals]
                elif key == "translate":
                    translate = np.array([float(v) for v in vals])
                elif key == "scale":
                    scale = float(vals[0])
                elif key == "data":
                    break
            raw = np.frombuffer(fh.read(), dtype=np.uint8)
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc})") from None
    except (ValueError, IndexError):
        raise InputError(f"{path}: malformed binvox header") from None
    if dims is None or len(dims) != 3 or len(raw) % 2:
        raise InputError(f"{path}: malformed binvox header or data")
    values, counts = raw[0::2], raw[1::2].astype(np.int64)
    if counts.sum() != np.prod(dims):
        raise InputError(f"{path}: run lengths cover {counts.sum()} voxels, expected {np.prod(dims)}")
    occ = np.repeat(values.astype(bool), counts).reshape(dims)
    # runs go x, then z, then y (y fastest): reorder to x, y, z
    return occ.transpose(0, 2, 1), (translate if translate is not None else np.zeros(3)), scale


def _taubin(v: np.ndarray, f: np.ndarray, iters: int, lam=0.5, mu=-0.53) -> np.ndarray:
    """Taubin's lambda/mu smoothing: removes the voxel staircase without shrinking the shape."""
    n = len(v)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    A = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    A = ((A + A.T) > 0).astype(np.float64)
    deg = np.asarray(A.sum(1)).ravel()
    W = sp.diags(1.0 / np.maximum(deg, 1)) @ A
    v = v.astype(np.float64)
    for _ in range(iters):
        v = v + lam * (W @ v - v)
        v = v + mu * (W @ v - v)
    return v


def _labels_for(path: str) -> dict:
    """Row of labels.csv (next to the voxel/ folder) whose file stem matches, else {}."""
    stem = os.path.splitext(os.path.basename(path))[0]
    folder = os.path.dirname(os.path.abspath(path))
    for root in (folder, os.path.dirname(folder)):
        table = _read_labels(os.path.join(root, "labels.csv"))
        if table:
            return table.get(stem, {})
    return {}


_LABEL_CACHE: dict = {}


def _read_labels(csv_path: str) -> dict:
    if csv_path not in _LABEL_CACHE:
        table = {}
        if os.path.exists(csv_path):
            with open(csv_path, newline="", encoding="utf-8") as fh:
                for row in csv.DictReader(fh):
                    stem = os.path.splitext(os.path.basename(row["file"]))[0]
                    table[stem] = {"style": row["style"], "category": row["category"]}
        _LABEL_CACHE[csv_path] = table
    return _LABEL_CACHE[csv_path]


def voxel_mesh(path, smooth_iters: int = 10, up: str = "z") -> Mesh:
    """Closed, smoothed surface of a binvox grid in world units, Z up, named by the file stem.

    The grid is padded by one empty voxel so marching cubes closes every surface (watertight).
    `up` is the grid's up axis in x, y, z order ('z' for the Hu 2017 set, see `read_binvox`)."""
    path = os.fspath(path)
    occ, translate, scale = read_binvox(path)
    if not occ.any():
        raise InputError(f"{path}: the voxel grid is empty")
    grid = np.pad(occ, 1).astype(np.float32)
    verts, faces, _, _ = marching_cubes(grid, level=0.5, allow_degenerate=False)
    verts = verts - 1.0                     # undo the padding: voxel centres at integer indices
    if smooth_iters > 0:
        verts = _taubin(verts, faces, smooth_iters)
    world = translate[None, :] + (verts + 0.5) / occ.shape[0] * scale
    stem = os.path.splitext(os.path.basename(path))[0]
    truth = dict(_labels_for(path))
    return Mesh(stem, up_to_z(world, up).astype(np.float32), faces.astype(np.int32),
                source=path, truth=truth)


def resolve_root(root=DEFAULT_ROOT) -> str:
    """A relative root is tried from the working folder, then from the repository root."""
    root = os.fspath(root)
    if os.path.isabs(root) or os.path.isdir(root):
        return root
    repo = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    return os.path.join(repo, root)


def load_hu2017(root=DEFAULT_ROOT, limit: int | None = None, per_class: int | None = None,
                seed: int = 0, smooth_iters: int = 10) -> list[Mesh]:
    """The labelled voxel set as meshes. `per_class` keeps at most that many shapes per style,
    `limit` at most that many in total; both subsets are stratified by (style, category) with
    a seeded draw, so a small subset still mixes every style with every category."""
    root = resolve_root(root)
    table_path = os.path.join(root, "labels.csv")
    if not os.path.exists(table_path):
        raise InputError(f"{root}: no labels.csv (is the data folder there?)")
    with open(table_path, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    rng = np.random.default_rng(seed)
    rows = [rows[i] for i in rng.permutation(len(rows))]
    # round-robin over (style, category) groups: any prefix is stratified
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["style"], r["category"]), []).append(r)
    keys = sorted(groups)
    ordered, depth = [], 0
    while any(depth < len(groups[k]) for k in keys):
        ordered += [groups[k][depth] for k in keys if depth < len(groups[k])]
        depth += 1
    if per_class is not None:
        seen: dict = {}
        kept = []
        for r in ordered:
            if seen.get(r["style"], 0) < per_class:
                seen[r["style"]] = seen.get(r["style"], 0) + 1
                kept.append(r)
        ordered = kept
    if limit is not None:
        ordered = ordered[:limit]
    return [voxel_mesh(os.path.join(root, r["file"]), smooth_iters) for r in ordered]
