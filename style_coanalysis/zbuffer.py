"""The fast drawing path: feature lines and visibility from one depth buffer per view, in numpy.

Why: Freestyle spends seconds a shape finding which edges are visible, and the other renderers
test a seed with a BVH query per camera (until one sees it). Here each view is rasterised once into a depth
buffer holding, per pixel, the nearest surface's depth and triangle; every visibility question
of that view (line samples, seeds) is then a vectorised lookup in it. No render engine, no Blender: the same function runs anywhere.

Lines are the ones Freestyle draws with this extension's settings (`render._setup_freestyle`):
- silhouettes: edges between a face turned towards the camera and one turned away (face normals,
  no smoothing, as `use_smoothness=False`);
- borders: edges of one face;
- creases: edges whose faces meet at a dihedral angle below `crease_angle_deg` (Freestyle's
  crease angle; Blender's default 134 degrees).
No suggestive contours (their definition needs curvature; Freestyle draws them).

Visibility: a line sample is seen when one of the 4 pixel centres around it holds nothing, a
surface no nearer than the sample less about one pixel's worth of depth (`TOL_PX`), or a face of
its edge (`seen_in_buffer`); seeds get the ray cast of the other renderers, with the buffer's
triangles as the candidate occluders (`ray_visible`).
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from .rig import project

# Part of the drawing cache's key for this renderer: bump when its output changes
VERSION = "zbuffer-2"
TOL_PX = 1.0                # depth slack, in pixels' worth of depth at the point
STEP_PX = 0.5               # spacing of the samples along a line, in pixels
MAX_PAIRS = 4_000_000       # (triangle, pixel) candidates rasterised at once (memory bound)


def _expand(counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For items with `counts`, every (item, k) with k < count: (items, ks), vectorised."""
    items = np.repeat(np.arange(len(counts)), counts)
    ks = np.arange(len(items)) - np.repeat(np.cumsum(counts) - counts, counts)
    return items, ks


def _spans(lo: np.ndarray, hi: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """Pixel indices whose centres (i + 0.5) lie in [lo, hi], clipped to the image: first, count."""
    first = np.clip(np.ceil(lo - 0.5), 0, size).astype(np.int64)
    last = np.clip(np.floor(hi - 0.5), -1, size - 1).astype(np.int64)
    return first, np.maximum(0, last - first + 1)


def rasterise(pixels: np.ndarray, depth: np.ndarray, faces: np.ndarray, size: int
              ) -> tuple[np.ndarray, np.ndarray]:
    """Depth buffer of one view: (size, size) nearest depth (inf: nothing) and triangle (-1).

    `pixels` (N, 2) and `depth` (N,) are the projected vertices (`rig.project`); a pixel is
    covered when its centre lies in the triangle. Scanlines: each triangle's rows, then the
    span of each row, so the work is the pixels covered (thin slanted triangles cost no more
    than their area). Depth is interpolated perspective-correctly (1/depth is linear).
    """
    zbuf = np.full(size * size, np.inf)
    tri_id = np.full(size * size, -1, np.int64)
    x, y = pixels[:, 0].astype(np.float64), pixels[:, 1].astype(np.float64)
    corners = [np.ascontiguousarray(faces[:, k]) for k in range(3)]
    xs, ys, ds = ([a[f] for f in corners] for a in (x, y, depth))     # per corner, 1-D columns
    # only the triangles whose box holds a pixel centre (fine meshes: many hold none)
    _, n_rows = _spans(np.minimum(np.minimum(*ys[:2]), ys[2]),
                       np.maximum(np.maximum(*ys[:2]), ys[2]), size)
    _, n_cols = _spans(np.minimum(np.minimum(*xs[:2]), xs[2]),
                       np.maximum(np.maximum(*xs[:2]), xs[2]), size)
    with np.errstate(invalid="ignore"):
        keep = np.flatnonzero((n_rows > 0) & (n_cols > 0) & (ds[0] > 0) & (ds[1] > 0) & (ds[2] > 0))
    xs, ys = [a[keep] for a in xs], [a[keep] for a in ys]
    inv = [1.0 / a[keep] for a in ds]
    # corners by height: a row's span runs from the long edge (top to bottom) to the top-middle
    # edge above the middle corner, and to the middle-bottom edge below it
    y0, y1, y2 = ys
    top = np.where((y0 <= y1) & (y0 <= y2), 0, np.where(y1 <= y2, 1, 2))
    bot = np.where((y2 >= y1) & (y2 >= y0), 2, np.where(y1 >= y0, 1, 0))
    mid = 3 - top - bot
    tx, ty, mx, my, bx, by = (np.choose(top, xs), np.choose(top, ys), np.choose(mid, xs),
                              np.choose(mid, ys), np.choose(bot, xs), np.choose(bot, ys))

    def slope(x0, y0, x1, y1):
        dy = y1 - y0
        return np.divide(x1 - x0, dy, out=np.zeros_like(dy), where=dy != 0)
    edges = np.stack([tx, ty, mx, my, slope(tx, ty, bx, by), slope(tx, ty, mx, my),
                      slope(mx, my, bx, by)], axis=1)
    row0, n_rows = _spans(ty, by, size)
    # 1/depth = plane . (x, y, 1) across each triangle (perspective-correct interpolation):
    # the plane through the points (x, y, 1/depth) of its corners
    ux, uy, uz = xs[1] - xs[0], ys[1] - ys[0], inv[1] - inv[0]
    vx, vy, vz = xs[2] - xs[0], ys[2] - ys[0], inv[2] - inv[0]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    flat = ~(np.abs(nz) > 1e-12)                                 # degenerate in the image, or NaN
    n_rows[flat] = 0
    nz = np.where(flat, 1.0, nz)
    plane = np.stack([-nx / nz, -ny / nz, (nx * xs[0] + ny * ys[0]) / nz + inv[0]], axis=1)
    # chunks of triangles with at most MAX_PAIRS rows between them (memory bound)
    ends = np.cumsum(n_rows)
    start = 0
    while start < len(keep):
        base = ends[start - 1] if start else 0
        stop = max(start + 1, int(np.searchsorted(ends, base + MAX_PAIRS, side="right")))
        t, k = _expand(n_rows[start:stop])
        t += start
        row = row0[t] + k
        y = row + 0.5
        tx, ty, mx, my, k_long, k_top, k_bot = edges[t].T
        x_long = tx + (y - ty) * k_long
        x_short = np.where(y < my, tx + (y - ty) * k_top, mx + (y - my) * k_bot)
        col0, n_cols = _spans(np.minimum(x_long, x_short), np.maximum(x_long, x_short), size)
        r, kc = _expand(n_cols)
        ids, row, col = t[r], row[r], col0[r] + kc
        pl = plane[ids]
        z = 1.0 / (pl[:, 0] * (col + 0.5) + pl[:, 1] * (row + 0.5) + pl[:, 2])
        pix = row * size + col
        np.minimum.at(zbuf, pix, z)
        won = z <= zbuf[pix]                # the nearest at its pixel (ties: the last)
        tri_id[pix[won]] = keep[ids[won]]
        start = stop
    return zbuf.reshape(size, size), tri_id.reshape(size, size)


def pad(zbuf: np.ndarray, tri_id: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A buffer with a one-pixel frame of nothing: what `seen_in_buffer` and `ray_visible` take."""
    h, w = zbuf.shape
    z = np.full((h + 2, w + 2), np.inf)
    t = np.full((h + 2, w + 2), -1, tri_id.dtype)
    z[1:-1, 1:-1], t[1:-1, 1:-1] = zbuf, tri_id
    return z, t


def _window(zbuf: np.ndarray, tri_id: np.ndarray, pixels: np.ndarray):
    """Per point: inside the image, and the depths and triangles (n, 4) of the 2x2 pixels whose
    centres surround it (`zbuf`, `tri_id` padded by `pad`)."""
    size = zbuf.shape[0] - 2
    finite = np.isfinite(pixels).all(axis=1)
    x = np.where(finite, pixels[:, 0], -10.0)
    y = np.where(finite, pixels[:, 1], -10.0)
    inside = finite & (x >= 0) & (x < size) & (y >= 0) & (y < size)
    col = np.floor(np.where(inside, x, 0.0) - 0.5).astype(np.int64) + 1    # padded index
    row = np.floor(np.where(inside, y, 0.0) - 0.5).astype(np.int64) + 1
    flat = (row * (size + 2) + col)[:, None] + np.array([0, 1, size + 2, size + 3])[None]
    return inside, zbuf.ravel()[flat], tri_id.ravel()[flat]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product (np.cross costs several times more on short rows)."""
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


def seen_in_buffer(zbuf: np.ndarray, tri_id: np.ndarray, pixels: np.ndarray, depth: np.ndarray,
                   own, focal_px: float) -> np.ndarray:
    """(n,) bool for line samples: one of the 4 pixel centres around the sample holds nothing, a
    surface no nearer than its depth less `TOL_PX` pixels' worth, or a triangle of its own
    (`own(tri_ids (n, 4)) -> bool (n, 4)`). Four, not one: a line lies on a depth edge, where
    the nearest pixel centre may fall on either side."""
    inside, z, t = _window(zbuf, tri_id, pixels)
    slack = (depth * (1.0 - TOL_PX / focal_px))[:, None]
    return inside & ((z >= slack) | ((t >= 0) & own(t))).any(axis=1)


def ray_visible(zbuf: np.ndarray, tri_id: np.ndarray, pixels: np.ndarray, points: np.ndarray,
                depth: np.ndarray, own_face: np.ndarray, camera: np.ndarray, triangles,
                neighbours: np.ndarray, focal_px: float) -> np.ndarray:
    """(n,) bool for surface points (seeds): `render.ray_visibility`'s ray cast, vectorised,
    with the depth buffer in place of a BVH.

    The buffer proposes the occluders: the triangles nearest the camera at the 4 pixel centres
    around the point's projection, and their edge neighbours (the surface along the exact ray
    may be a neighbour's). A point is hidden when the segment from the camera to it crosses
    one of them short of the point by more than `TOL_PX` pixels' worth of depth. Only points
    with a nearer surface (not the face they lie on, `own_face`) at some but not
    all of the 4 pixel centres are tested exactly: with none they are seen, with nearer
    surfaces all around they are hidden. `triangles`: (first corner, first edge, second edge)
    per face, each (M, 3).
    """
    corner, edge1, edge2 = triangles
    inside, z, t = _window(zbuf, tri_id, pixels)
    slack = depth * (1.0 - TOL_PX / focal_px)
    nearer = (t >= 0) & (z < slack[:, None])
    r, k = np.nonzero(nearer)
    mine = t[r, k] == own_face[r]
    nearer[r[mine], k[mine]] = False
    seen = inside & ~nearer.all(axis=1)         # covered all around by nearer surfaces: hidden
    doubt = np.flatnonzero(seen & nearer.any(axis=1))
    if len(doubt) == 0:
        return seen
    cand = t[doubt]
    ring = neighbours[np.maximum(cand, 0)].reshape(len(doubt), -1)
    ring[np.repeat(cand < 0, neighbours.shape[1], axis=1)] = -1
    cand = np.sort(np.concatenate([cand, ring], axis=1), axis=1)
    cand[:, 1:][cand[:, 1:] == cand[:, :-1]] = -1
    r, k = np.nonzero(cand >= 0)
    tris, r = cand[r, k], doubt[r]
    # Moller-Trumbore (a triangle the point lies on is crossed at the point itself, s = 1,
    # so it never counts) on camera + s (point - camera): hidden if 0 < s < 1 - TOL_PX / focal_px
    v0, e1, e2 = corner[tris], edge1[tris], edge2[tris]
    d = points[r] - camera
    pvec = _cross(d, e2)
    det = np.einsum("ij,ij->i", e1, pvec)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        tvec = camera - v0
        u = np.einsum("ij,ij->i", tvec, pvec) * inv
        qvec = _cross(tvec, e1)
        v = np.einsum("ij,ij->i", d, qvec) * inv
        s_hit = np.einsum("ij,ij->i", e2, qvec) * inv
    hit = (np.abs(det) > 1e-15) & (u >= 0) & (v >= 0) & (u + v <= 1) & (s_hit > 0) \
        & (s_hit < 1.0 - TOL_PX / focal_px)
    seen[r[hit]] = False
    return seen


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    v = vertices.astype(np.float64)[faces]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def edges_with_faces(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unique edges (E, 2), their first two faces (E, 2) (-1 where an edge has one face), and
    whether each edge is closed: exactly two faces, running it in opposite directions."""
    m = len(faces)
    half = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2).astype(np.int64)
    forward = half[:, 0] < half[:, 1]
    e = np.sort(half, axis=1)
    f = np.repeat(np.arange(m), 3)
    key = e[:, 0] * (int(faces.max()) + 1) + e[:, 1]
    order = np.argsort(key, kind="stable")
    key, e, f, forward = key[order], e[order], f[order], forward[order]
    first = np.r_[True, key[1:] != key[:-1]]
    starts = np.flatnonzero(first)
    counts = np.diff(np.r_[starts, len(key)])
    nxt = np.minimum(starts + 1, len(f) - 1)
    second = np.where(counts >= 2, f[nxt], -1)
    closed = (counts == 2) & (forward[starts] != forward[nxt])
    return e[starts], np.stack([f[starts], second], axis=1), closed


def face_neighbours(edge_faces: np.ndarray, n_faces: int) -> np.ndarray:
    """(n_faces, 3) faces sharing an edge with each face (-1 where none)."""
    pairs = edge_faces[edge_faces[:, 1] >= 0]
    both = np.concatenate([pairs, pairs[:, ::-1]])
    both = both[np.argsort(both[:, 0], kind="stable")]
    slot = np.arange(len(both)) - np.searchsorted(both[:, 0], both[:, 0])
    out = np.full((n_faces, 3), -1, np.int64)
    keep = slot < 3
    out[both[keep, 0], slot[keep]] = both[keep, 1]
    return out


def closed_outwards(vertices: np.ndarray, faces: np.ndarray, edge_faces: np.ndarray,
                    edge_closed: np.ndarray) -> np.ndarray:
    """(M,) bool per face: does it belong to a closed part turned outwards? A part (faces joined
    by edges) is closed when each of its edges is (`edges_with_faces`), and turned outwards
    when its volume is positive. From outside such a part only its front faces can be seen."""
    m = len(faces)
    pairs = edge_faces[edge_faces[:, 1] >= 0]
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), (m, m))
    n_parts, part = connected_components(graph, directed=False)
    open_part = np.zeros(n_parts, bool)
    open_part[part[edge_faces[~edge_closed, 0]]] = True
    v = vertices[faces]
    volume = np.einsum("ij,ij->i", v[:, 0], _cross(v[:, 1], v[:, 2]))
    inward = np.bincount(part, weights=volume, minlength=n_parts) <= 0
    return ~(open_part | inward)[part]


class ShapeBuffers:
    """One shape's depth buffers for every camera, and what they answer."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, cameras: np.ndarray,
                 locations: np.ndarray, size: int, focal_px: float,
                 turned_from: "ShapeBuffers | None" = None):
        """`turned_from`: the buffers of the same faces with the vertices turned otherwise
        (another quarter of the rig), whose topology and closed parts these share rather than
        find again (a turn keeps both: each part's volume keeps its sign)."""
        self.vertices = np.asarray(vertices, np.float64)
        self.faces = np.asarray(faces, np.int64)
        self.cameras, self.locations = cameras, locations
        self.size, self.focal_px = size, focal_px
        self.normals = face_normals(self.vertices, self.faces)
        corners = self.vertices[self.faces]
        self.centres = corners.mean(axis=1)
        self.triangles = (corners[:, 0], corners[:, 1] - corners[:, 0],
                          corners[:, 2] - corners[:, 0])
        if turned_from is not None:
            self.edges, self.edge_faces = turned_from.edges, turned_from.edge_faces
            self.neighbours, self.closed = turned_from.neighbours, turned_from.closed
        else:
            self.edges, self.edge_faces, edge_closed = edges_with_faces(self.faces)
            self.neighbours = face_neighbours(self.edge_faces, len(self.faces))
            # a closed surface turned outwards is only ever seen from its front faces: the back
            # faces can be left out of the buffers (half the work), which stay the same
            self.closed = closed_outwards(self.vertices, self.faces, self.edge_faces, edge_closed)
        pix, depth = project(cameras, self.vertices)
        self.buffers = []
        for v in range(len(cameras)):
            keep = np.flatnonzero(self.facing_mask(v) | ~self.closed)
            zbuf, local = rasterise(pix[v], depth[v], self.faces[keep], size)
            self.buffers.append(pad(zbuf, np.where(local >= 0, keep[local], -1)))

    def facing_mask(self, v: int) -> np.ndarray:
        """(M,) bool: is each face turned towards camera v?"""
        return np.einsum("ij,ij->i", self.normals, self.locations[v] - self.centres) > 0

    def points_visible(self, points: np.ndarray, own_face: np.ndarray) -> np.ndarray:
        """(V, n) bool for surface points lying on the faces `own_face` (seeds)."""
        points = np.asarray(points, np.float64).reshape(-1, 3)
        own_face = np.asarray(own_face)
        out = np.zeros((len(self.cameras), len(points)), bool)
        for v in range(len(self.cameras)):
            pix, depth = project(self.cameras[v:v + 1], points)
            out[v] = ray_visible(*self.buffers[v], pix[0], points, depth[0], own_face,
                                 self.locations[v], self.triangles, self.neighbours,
                                 self.focal_px)
        return out

    def points_seen_by_any(self, points: np.ndarray, own_face: np.ndarray) -> np.ndarray:
        """(n,) bool: `points_visible(...).any(axis=0)`, each view testing only the points no
        earlier view saw (a point's answer does not depend on the others tested with it)."""
        points = np.asarray(points, np.float64).reshape(-1, 3)
        own_face = np.asarray(own_face)
        seen = np.zeros(len(points), bool)
        for v in range(len(self.cameras)):
            rest = np.flatnonzero(~seen)
            if len(rest) == 0:
                break
            pix, depth = project(self.cameras[v:v + 1], points[rest])
            seen[rest] = ray_visible(*self.buffers[v], pix[0], points[rest], depth[0],
                                     own_face[rest], self.locations[v], self.triangles,
                                     self.neighbours, self.focal_px)
        return seen

    def lines(self, crease_angle_deg: float) -> np.ndarray:
        """(V, size, size) float32 ink: visible silhouettes, borders and creases, 1 px wide."""
        edges, ef = self.edges, self.edge_faces
        normals = self.normals
        border = ef[:, 1] < 0
        f1 = np.where(border, ef[:, 0], ef[:, 1])
        cos = np.einsum("ij,ij->i", normals[ef[:, 0]], normals[f1])
        crease = ~border & (cos < np.cos(np.radians(180.0 - crease_angle_deg)))
        images = np.zeros((len(self.cameras), self.size, self.size), np.float32)
        for v in range(len(self.cameras)):
            facing = self.facing_mask(v)
            silhouette = ~border & (facing[ef[:, 0]] != facing[f1])
            pick = border | crease | silhouette
            # on a closed part, edges between back faces are hidden
            pick &= facing[ef[:, 0]] | facing[f1] | ~self.closed[ef[:, 0]]
            images[v] = self._draw_edges(v, edges[pick], ef[pick])
        return images

    def _draw_edges(self, v: int, edges: np.ndarray, edge_faces: np.ndarray) -> np.ndarray:
        img = np.zeros((self.size, self.size), np.float32)
        if len(edges) == 0:
            return img
        cam = self.cameras[v]
        # projection is linear in homogeneous coordinates: interpolate there
        ha = np.c_[self.vertices[edges[:, 0]], np.ones(len(edges))] @ cam.T      # (E, 3)
        hb = np.c_[self.vertices[edges[:, 1]], np.ones(len(edges))] @ cam.T
        with np.errstate(divide="ignore", invalid="ignore"):
            length = np.linalg.norm(ha[:, :2] / ha[:, 2:] - hb[:, :2] / hb[:, 2:], axis=1)
        n = np.where(np.isfinite(length), np.ceil(length / STEP_PX), 1).astype(np.int64) + 1
        ids, local = _expand(n)
        t = (local / (n[ids] - 1))[:, None]
        h = ha[ids] + t * (hb[ids] - ha[ids])
        depth = h[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            pix = h[:, :2] / depth[:, None]
        f0, f1 = edge_faces[ids, 0][:, None], edge_faces[ids, 1][:, None]
        seen = seen_in_buffer(*self.buffers[v], pix, depth,
                              lambda t: (t == f0) | (t == f1), self.focal_px)
        cols = np.floor(pix[seen, 0]).astype(np.int64)
        rows = np.floor(pix[seen, 1]).astype(np.int64)
        img[rows, cols] = 1.0
        return img
