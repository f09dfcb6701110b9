"""Surface seeds (paper 4.1): points spread evenly over a shape's surface.

The paper samples 3D points rather than 2D pixels so that patches cover the surface uniformly
and can be back-projected later. Plain area-weighted random sampling clumps (some seeds nearly
coincide, some regions get none), so we draw many area-weighted candidates, start from a
farthest-point subset (kept apart, but it favours corners and rims), then relax it with k-means
(Lloyd) over the candidates until it settles and snap each centre to its nearest candidate:
every seed lies on the surface, density follows area, seeds keep apart without piling onto edges.

Deterministic for a given seed, and stable (issue 11): the candidates are placed by face and a
hash, not by a draw from the running sum of the face areas (`sample_surface`), and the
farthest-point walk starts from a place on the shape (the candidate farthest from their
centroid), not from a drawn index, so a candidate that the visibility filter keeps or drops after
a small change of coordinates moves the seeds near it at most. Measured on 60 sample shapes, 90
seeds, no visibility filter: seeds that moved on a mesh written to OBJ and read back, 50 shapes
before, 8 now; with coordinates x 1.0000001, 11 before, none now.
"""
from __future__ import annotations

import warnings
from typing import Callable

import numpy as np
from scipy.cluster.vq import kmeans2

from .hashing import uniform
from .meshes import InputError, Mesh, face_areas

CANDIDATES_PER_SEED = 40     # enough candidates that the farthest-point pick is nearly even
MIN_CANDIDATES = 2000
LLOYD_MAX_STEPS = 300        # relaxation steps at most (they settle in about 20-30)


def sample_surface(vertices: np.ndarray, faces: np.ndarray, n: int,
                   seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """About `n` points spread over the triangles by area: (points (m,3) float64, faces (m,)).

    Each face gets floor(n * area share + u) points, u a uniform number of its own (systematic
    sampling: the expected count is n * share), at barycentric coordinates drawn from a hash of
    (face, point, seed). Nothing depends on a running sum over all faces, so a 1e-6 change of
    the coordinates (a mesh written to OBJ and read back) moves the points by as much and
    changes a count only where n * share + u sits within 1e-6 of an integer; a draw from the
    cumulative areas (numpy's choice) put several of a shape's 3,600 candidates on other faces."""
    areas = face_areas(vertices, faces)
    total = areas.sum()
    if not total > 0:
        raise InputError("cannot sample a surface with zero area")
    f = np.arange(len(faces))
    counts = np.floor(n * areas / total + uniform(f, 0, seed)).astype(np.int64)
    face_idx = np.repeat(np.arange(len(faces)), counts)
    k = np.arange(len(face_idx)) - np.repeat(np.cumsum(counts) - counts, counts)
    u = uniform(face_idx, 2 * k + 1, seed)
    v = uniform(face_idx, 2 * k + 2, seed)
    # uniform barycentric coordinates by folding the unit square onto the triangle
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


def sample_seeds(mesh: Mesh, n: int, seed: int = 0,
                 keep: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
                 ) -> tuple[np.ndarray, np.ndarray]:
    """`n` seeds on `mesh`'s surface, spread by area and kept apart.

    `keep(points, faces) -> bool mask` may drop candidates first: the renderer passes "seen by
    at least one camera", since a seed buried between overlapping parts yields no patch in any
    view (on the sample furniture over half the area is such hidden surface). If it keeps
    nothing, all candidates are used. Returns (points (n, 3) float32, face_idx (n,) int32).
    Same mesh, seed and filter -> same seeds.
    """
    if n <= 0:
        return np.zeros((0, 3), np.float32), np.zeros(0, np.int32)
    m = max(MIN_CANDIDATES, CANDIDATES_PER_SEED * n)
    cand, cand_faces = sample_surface(mesh.vertices, mesh.faces, m, seed)
    if keep is not None:
        mask = np.asarray(keep(cand, cand_faces), bool)
        if mask.sum() >= n:
            cand, cand_faces = cand[mask], cand_faces[mask]
    start = int(np.argmax(np.linalg.norm(cand - cand.mean(axis=0), axis=1)))
    pick = farthest_point_order(cand, n, start=start)
    if n < 2:
        return cand[pick].astype(np.float32), cand_faces[pick].astype(np.int32)
    # Lloyd from the farthest-point start until a step moves no centre (a fixed point: its
    # labels are the final centres' own); an emptied cluster is topped up below
    centres = cand[pick]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(LLOYD_MAX_STEPS):
            moved, labels = kmeans2(cand, centres, iter=1, minit="matrix", missing="warn")
            settled = np.array_equal(moved, centres)
            centres = moved
            if settled:
                break
        else:
            _, labels = kmeans2(cand, centres, iter=1, minit="matrix", missing="warn")
    # snap every centre to the nearest candidate of its own cluster (distinct, on the surface)
    d = np.linalg.norm(cand - centres[labels], axis=1)
    order = np.lexsort((d, labels))
    first = order[np.r_[True, labels[order][1:] != labels[order][:-1]]]
    if len(first) < len(pick):          # a cluster emptied: top up with farthest candidates
        dist = np.min(np.linalg.norm(cand[:, None] - cand[first][None], axis=2), axis=1)
        extra = []
        for _ in range(len(pick) - len(first)):
            extra.append(int(np.argmax(dist)))
            dist = np.minimum(dist, np.linalg.norm(cand - cand[extra[-1]], axis=1))
        first = np.concatenate([first, extra])
    return cand[first].astype(np.float32), cand_faces[first].astype(np.int32)
