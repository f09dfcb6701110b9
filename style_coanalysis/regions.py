"""Style regions on the surface, per face (paper 4.5 back-projection and the 5.3
"patch-to-region extension").

Why per face and per pixel rather than per vertex: a 24-pixel style window spans plain surface
around the ornament it matched, and a large plain face's vertices sit at its corners, often on
the ornament's border; marking the vertices under the windows therefore painted large plain faces
(area precision 0.41 on the sample, 0.12 on collection2, below chance there). Here each view's
face buffer (which face is seen at each pixel, depth-tested) says which faces the evidence lies
on, accumulated over every view that sees them, so a face counts only by its own visible pixels.

Two kinds of evidence, because the two generated collections disagree on which one works
(bench/bench_localisation.py; each alone is at chance on one of them):

* window cover: the share of a face's visible pixels under its cluster's style windows (the
  matched style patches). Ornament drawn mostly by its outline (a cabriole leg) is found so.
* carved regions: connected regions of faces densely covered by interior strokes (ink away from
  silhouettes, which say where a part ends, not what is carved on it) that hold at least one
  face marked by the window cover. This is the patch-to-region extension: a matched style patch
  marks the whole carved region it lies on, and the region stops where the strokes stop, at the
  plain surface around it. (Seeding from the cover rather than from style-window strokes: area
  IoU 0.35 vs 0.33 on the sample, 0.47 vs 0.39 on collection2, exploration with seed 0.)

Before either test the per-face densities are diffused a few steps over the face adjacency, so
faces too small to own a pixel at 200 px take their neighbours' value; measured faces keep
theirs. The user's mesh is only read.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage, sparse
from scipy.sparse.csgraph import connected_components

from .rig import project
from .zbuffer import rasterise


@dataclass
class RegionParams:
    """How surface evidence becomes style regions (see the module docstring)."""

    cover: float = 0.8            # share of a face's seen pixels under style windows
    stroke_density: float = 0.5   # interior ink per seen interior pixel of a carved region
    depth_jump: float = 0.1       # depth step (unit-sphere frame) that makes a silhouette
    dilate: int = 1               # pixels a stroke is widened by (a line sits on a face's edge)
    smooth_steps: int = 4         # diffusion steps over the face adjacency


def face_weights(vertices, faces, cameras, images, cover, params: RegionParams = RegionParams()):
    """(M,) float32 style weight per face in [0, 1], > 0.5 on style regions.

    cameras (V, 3, 4), images (V, H, W) ink, cover (V, H, W) bool: pixels under the shape's
    style windows."""
    faces = np.asarray(faces)
    n = len(faces)
    buffers, depth = face_buffers(vertices, faces, cameras, images.shape[-1])
    ink = np.asarray(images) > 0.5
    grow = ndimage.generate_binary_structure(2, 1)
    outline = outline_pixels(depth, params.depth_jump)
    outline = np.stack([ndimage.binary_dilation(o, grow) for o in outline])
    seen, under = face_evidence(buffers, n, cover, dilate=0)
    seen_in, strokes = face_evidence(buffers, n, ink & ~outline, params.dilate, where=~outline)
    adj = face_adjacency(faces, len(vertices))
    cov = extend(under, seen, adj, params.smooth_steps)
    dense = extend(strokes, seen_in, adj, params.smooth_steps)
    carved = seeded_components(dense > params.stroke_density, cov > params.cover, adj)
    w = np.clip(cov / (2 * params.cover), 0, 1)
    w = np.maximum(w, np.where(carved, 0.5 + 0.5 * np.clip(dense, 0, 1), 0.0))
    return w.astype(np.float32)


def face_buffers(vertices, faces, cameras, size: int):
    """(V, size, size) face buffers (the triangle seen at each pixel centre, -1: background)
    and depth buffers (inf: background) of every view: `zbuffer.rasterise`, the same depth
    buffer the numpy drawing path draws with."""
    pix, depth = project(cameras, vertices)
    out = [rasterise(pix[v], depth[v], np.asarray(faces), size) for v in range(len(cameras))]
    return np.stack([f for _, f in out]), np.stack([z for z, _ in out])


def outline_pixels(depth: np.ndarray, jump: float) -> np.ndarray:
    """(V, H, W) bool: pixels next to the background or to a depth jump above `jump` (in the
    normalised frame, where the shape fits the unit sphere): where silhouettes are drawn.
    Their strokes say where a part ends, not what is carved on it."""
    pad = np.pad(depth, ((0, 0), (1, 1), (1, 1)), constant_values=np.inf)
    centre = pad[:, 1:-1, 1:-1]
    out = np.zeros(depth.shape, bool)
    for dy, dx in ((0, 1), (2, 1), (1, 0), (1, 2)):
        other = pad[:, dy:dy + depth.shape[1], dx:dx + depth.shape[2]]
        with np.errstate(invalid="ignore"):
            out |= ~np.isfinite(other) | (np.abs(other - centre) > jump)
    return out & np.isfinite(centre)


def face_evidence(buffers: np.ndarray, n_faces: int, marks: np.ndarray, dilate: int = 0,
                  where: np.ndarray | None = None):
    """Per face, summed over the views: pixels where it is seen (within `where`, if given),
    and those of them marked. marks: (V, H, W) bool, widened by `dilate` pixels (a stroke drawn
    along an edge lies half on the neighbouring face)."""
    seen = np.zeros(n_faces)
    marked = np.zeros(n_faces)
    grow = ndimage.generate_binary_structure(2, 1)
    for v, (buf, mark) in enumerate(zip(buffers, marks)):
        mask = ndimage.binary_dilation(mark, grow, iterations=dilate) if dilate else mark
        on = buf >= 0 if where is None else (buf >= 0) & where[v]
        seen += np.bincount(buf[on], minlength=n_faces)
        marked += np.bincount(buf[on & mask], minlength=n_faces)
    return seen, marked


def face_adjacency(faces: np.ndarray, n_vertices: int) -> sparse.csr_matrix:
    """Faces sharing an edge (symmetric, no self loops)."""
    faces = np.asarray(faces)
    m = len(faces)
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    key = edges[:, 0].astype(np.int64) * n_vertices + edges[:, 1]
    owner = np.tile(np.arange(m), 3)
    order = np.argsort(key, kind="stable")
    key, owner = key[order], owner[order]
    same = np.flatnonzero(key[1:] == key[:-1])
    a, b = owner[same], owner[same + 1]
    adj = sparse.coo_matrix((np.ones(len(a)), (a, b)), shape=(m, m))
    adj = ((adj + adj.T) > 0).astype(np.float64)
    adj.setdiag(0)
    adj.eliminate_zeros()
    return adj.tocsr()


def extend(marked: np.ndarray, seen: np.ndarray, adjacency, steps: int) -> np.ndarray:
    """Per-face density marked/seen; faces never seen (too small to own a pixel, or hidden)
    take the mean of their neighbours' density, spreading up to `steps` faces in from the
    measured ones. Measured faces keep their value."""
    known = seen > 0
    density = np.where(known, marked / np.maximum(seen, 1), 0.0)
    value, weight = density.copy(), known.astype(np.float64)
    a = adjacency + sparse.identity(adjacency.shape[0], format="csr")
    for _ in range(steps):
        value, weight = a @ value, a @ weight
        filled = weight > 0
        value = np.where(filled, value / np.maximum(weight, 1e-12), 0.0)
        value = np.where(known, density, value)
        weight = filled.astype(np.float64)
    return value


def seeded_components(mask: np.ndarray, seed: np.ndarray, adjacency) -> np.ndarray:
    """The faces of `mask` whose connected region (over the adjacency, inside the mask) holds
    at least one `seed` face."""
    idx = np.flatnonzero(mask)
    out = np.zeros(len(mask), bool)
    if len(idx) == 0:
        return out
    n, label = connected_components(adjacency[idx][:, idx], directed=False)
    seeded = np.bincount(label, seed[idx].astype(np.float64), minlength=n) > 0
    out[idx[seeded[label]]] = True
    return out


def vertex_weights(face_w: np.ndarray, faces: np.ndarray, areas: np.ndarray, n_vertices: int):
    """Per-vertex weight: the area-weighted mean of its faces' weights (the vertex group)."""
    idx = np.asarray(faces).ravel()
    num = np.bincount(idx, np.repeat(areas * face_w, 3), minlength=n_vertices)
    den = np.bincount(idx, np.repeat(areas, 3), minlength=n_vertices)
    return np.where(den > 0, num / np.maximum(den, 1e-30), 0.0).astype(np.float32)
