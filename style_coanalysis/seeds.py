"""Surface seeds (paper 4.1): points spread evenly over a shape's surface.

The paper samples 3D points rather than 2D pixels so that patches cover the surface uniformly
and can be back-projected later. Plain area-weighted random sampling clumps (some seeds nearly
coincide, some regions get none), so we draw many area-weighted candidates and keep a
farthest-point subset of them: every seed lies on the surface, density follows area, and seeds
keep apart. Deterministic for a given seed.
"""
from __future__ import annotations

import numpy as np

from .meshes import InputError, Mesh, face_areas

CANDIDATES_PER_SEED = 40     # enough candidates that the farthest-point pick is nearly even
MIN_CANDIDATES = 2000


def sample_surface(vertices: np.ndarray, faces: np.ndarray, n: int,
                   rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """`n` area-weighted uniform random points on the triangles: (points (n,3) float64, faces (n,))."""
    areas = face_areas(vertices, faces)
    total = areas.sum()
    if not total > 0:
        raise InputError("cannot sample a surface with zero area")
    face_idx = rng.choice(len(faces), size=n, p=areas / total)
    # uniform barycentric coordinates by folding the unit square onto the triangle
    u, v = rng.random(n), rng.random(n)
    fold = u + v > 1.0
    u[fold], v[fold] = 1.0 - u[fold], 1.0 - v[fold]
    tri = vertices[faces[face_idx]].astype(np.float64)
    points = tri[:, 0] + u[:, None] * (tri[:, 1] - tri[:, 0]) + v[:, None] * (tri[:, 2] - tri[:, 0])
    return points, face_idx


def farthest_point_order(points: np.ndarray, n: int, start: int = 0) -> np.ndarray:
    """Indices of `n` points picked greedily, each the farthest from those already picked."""
    n = min(n, len(points))
    chosen = np.empty(n, dtype=np.int64)
    chosen[0] = start
    dist = np.linalg.norm(points - points[start], axis=1)
    for k in range(1, n):
        chosen[k] = int(np.argmax(dist))
        dist = np.minimum(dist, np.linalg.norm(points - points[chosen[k]], axis=1))
    return chosen


def sample_seeds(mesh: Mesh, n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """`n` seeds on `mesh`'s surface, spread by area and kept apart.

    Returns (points (n, 3) float32, face_idx (n,) int32). Same mesh and seed -> same seeds.
    """
    if n <= 0:
        return np.zeros((0, 3), np.float32), np.zeros(0, np.int32)
    rng = np.random.default_rng(seed)
    m = max(MIN_CANDIDATES, CANDIDATES_PER_SEED * n)
    cand, cand_faces = sample_surface(mesh.vertices, mesh.faces, m, rng)
    pick = farthest_point_order(cand, n, start=int(rng.integers(m)))
    return cand[pick].astype(np.float32), cand_faces[pick].astype(np.int32)
