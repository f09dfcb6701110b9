"""The plain mesh the whole pipeline speaks: a name, float32 vertices, int32 triangles.

Nothing here knows about Blender. The adapter layer turns objects and files into `Mesh`; the
analysis only ever sees these arrays. Validation lives here so every entry point refuses the
same bad input with the same message, naming the shape.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np


class InputError(ValueError):
    """Bad input a person can act on: the message names the object or file and the problem."""


@dataclass
class Mesh:
    """A triangle mesh with a name. `truth` holds ground truth when the input carries it
    (keys: 'style', 'category', 'face_mask' (bool per face)); the analysis never reads it.

    The vertices are relative to `origin` (world position = vertices + origin); from a Blender
    object, its own coordinates with its rotation and scale applied, its location kept apart. In
    world coordinates a shape 20 units from the world origin loses float32 bits to its
    position, and a few of its vertices then fall on the other side of the normalised frame's
    grid (`normalise`) and draw other pixels: the benchmark's shapes read back from a .blend,
    which lays them out on a grid, moved the partition (ARI down to 0.69). Kept apart, moving
    an object changes nothing the analysis sees."""

    name: str
    vertices: np.ndarray                  # (N, 3) float32, relative to origin
    faces: np.ndarray                     # (M, 3) int32, triangles
    source: str = ""                      # file path or Blender object name it came from
    truth: dict = field(default_factory=dict)
    origin: np.ndarray = field(default_factory=lambda: np.zeros(3))   # (3,) float64, world

    def __post_init__(self):
        self.vertices = np.ascontiguousarray(self.vertices, dtype=np.float32).reshape(-1, 3)
        self.faces = np.ascontiguousarray(self.faces, dtype=np.int32).reshape(-1, 3)
        self.origin = np.asarray(self.origin, dtype=np.float64).reshape(3)

    def content_hash(self) -> str:
        """Digest of the geometry only: the cache key's mesh part (names, truth and origin
        excluded: the drawings do not depend on where the shape sits)."""
        h = hashlib.sha256()
        h.update(np.int64(len(self.vertices)).tobytes())
        h.update(self.vertices.tobytes())
        h.update(self.faces.tobytes())
        return h.hexdigest()[:32]


def triangulate(polygons) -> np.ndarray:
    """Fan-triangulate a list of index sequences (convex polygons, as OBJ files hold them)."""
    tris = []
    for poly in polygons:
        for k in range(1, len(poly) - 1):
            tris.append((poly[0], poly[k], poly[k + 1]))
    return np.asarray(tris, dtype=np.int32).reshape(-1, 3)


def face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area of each triangle (float64)."""
    v = vertices.astype(np.float64)
    a, b, c = v[faces[:, 0]], v[faces[:, 1]], v[faces[:, 2]]
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def validate(mesh: Mesh) -> None:
    """Raise InputError naming the mesh if it cannot be analysed."""
    name = mesh.name
    if len(mesh.vertices) == 0 or len(mesh.faces) == 0:
        raise InputError(f"'{name}' has no faces")
    if not np.all(np.isfinite(mesh.vertices)):
        bad = int((~np.isfinite(mesh.vertices)).any(axis=1).sum())
        raise InputError(f"'{name}' has {bad} vertices with NaN or infinite coordinates")
    if mesh.faces.min() < 0 or mesh.faces.max() >= len(mesh.vertices):
        raise InputError(f"'{name}' has faces that index missing vertices")
    area = face_areas(mesh.vertices, mesh.faces).sum()
    extent = np.ptp(mesh.vertices, axis=0).max()
    if not area > 0 or not extent > 0:
        raise InputError(f"'{name}' is degenerate (zero surface area)")


NORMALISED_GRID = 2.0 ** -12     # normalised coordinates are multiples of this (`normalise`)


def up_to_z(vertices: np.ndarray, up: str) -> np.ndarray:
    """Rotate a Y-up asset so that its up axis is +Z (right-handed: (x, y, z) -> (x, -z, y))."""
    if up == "z":
        return vertices
    if up == "y":
        return np.stack([vertices[:, 0], -vertices[:, 2], vertices[:, 1]], axis=1)
    raise InputError(f"unknown up axis '{up}' (use 'z' or 'y')")


def surface_centroid(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted centroid of the surface: robust to uneven tessellation."""
    areas = face_areas(vertices, faces)
    centres = vertices[faces].astype(np.float64).mean(axis=1)
    total = areas.sum()
    if total <= 0:
        return vertices.astype(np.float64).mean(axis=0)
    return (centres * areas[:, None]).sum(axis=0) / total


def _frame(mesh: Mesh, up: str) -> tuple[np.ndarray, np.ndarray, float]:
    """The vertices in the +Z-up frame (relative to the origin), their surface centroid and
    the radius about it."""
    v = up_to_z(mesh.vertices.astype(np.float64), up)
    c = surface_centroid(v, mesh.faces)
    return v, c, float(np.linalg.norm(v - c, axis=1).max())


def normalisation(mesh: Mesh, up: str = "z") -> tuple[np.ndarray, float]:
    """(centre, radius) of the normalised frame in world space, in the +Z-up frame:
    normalised = (world' - c) / r, rounded to NORMALISED_GRID by `normalise` (so `to_world`
    maps it back to within half a grid step of r)."""
    _, c, r = _frame(mesh, up)
    return c + up_to_z(mesh.origin[None], up)[0], r


def to_world(points: np.ndarray, centre: np.ndarray, radius: float, up: str = "z") -> np.ndarray:
    """Map points (or directions, with centre 0 and radius 1) from the normalised frame back."""
    p = np.asarray(points, np.float64) * radius + centre
    if up == "y":  # inverse of up_to_z: (x, y, z) -> (x, z, -y)
        p = np.stack([p[..., 0], p[..., 2], -p[..., 1]], axis=-1)
    return p


def normalise(mesh: Mesh, up: str = "z") -> Mesh:
    """Upright (+Z), centred on the surface centroid, scaled into the unit sphere, rounded to
    a grid of NORMALISED_GRID.

    The paper assumes upright but not aligned shapes; real files range over three orders of
    magnitude in size and sit anywhere in space, so every shape is brought to one frame.
    Vertices are expected in world orientation and scale (the adapter applies object
    transforms first); where the shape sits (`Mesh.origin`) does not matter.
    Why the grid: the renderer redraws lines by a pixel for a change of a float32's last bit,
    and the same shape scaled by 1.0000001 or read back from an OBJ file (6 decimals) is not
    the same bits (on 24 sample shapes: 19 and 24 of them drew some other pixels; with the grid
    0 and 2). The grid is a fortieth of a pixel of the 200 px drawings, and about a hundred
    times a 6-decimal file's rounding of a 0.4-unit shape.
    """
    validate(mesh)
    v, c, r = _frame(mesh, up)          # the origin drops out: relative to the centroid
    v = (v - c) / r
    v = np.round(v / NORMALISED_GRID) * NORMALISED_GRID
    return Mesh(mesh.name, v.astype(np.float32), mesh.faces, mesh.source, mesh.truth)
