"""A second, independently made, labelled furniture collection for checking generalisation.

Why: a style analysis tuned on one generated collection may have learnt that collection's
quirks. This module builds a different collection (other styles, other categories, other
ornament vocabulary, other tessellation habits) so a result can be re-measured on shapes the
method was never tuned on. It was written from a short spec only, WITHOUT reading the other
generator (`style_coanalysis/sample.py`), the pipeline or any benchmark.

Spec in short:

* ``generate(size=120, seed=0, styles=None, categories=None) -> list[Mesh]``: ``size`` shapes
  spread round-robin over the chosen (style, category) grid visited in a seeded random order;
  fully deterministic for a seed, on every processor; unknown style/category names raise
  ``ValueError``.
* ``STYLES`` = barleytwist (spiral-twisted legs, posts, stretchers and a rail or two),
  shellcarved (plain square legs; fan/shell carvings in relief and scalloped fan crests),
  spindle (galleries of thin beaded spindles between rails), spadefoot (tapered square legs on
  inverted-pyramid spade feet; pierced splats, i.e. boards with cut-out openings).
* ``CATEGORIES`` = desk, bench, armchair, bookcase, sidetable, built of boxes, tubes and boards
  whose proportions (width, depth, height, leg thickness, shelves, drawers, ...) are drawn from
  a random stream that does not depend on the style.
* Global randomisation independent of style: a log-uniform unit scale in [0.3, 300], a yaw in
  [0, 360) degrees about +Z, and a random total triangle count in [3000, 10000] reached by
  subdividing the faces of plain boxes into coplanar grids (ornament tessellation also adapts).
* Z is up and the object stands on z = 0; parts are separate, possibly interpenetrating solids;
  no zero-area triangles; outward winding.
* Names ``c2_000``, ``c2_001``, ... in a shuffled order (they say nothing about the label).
* ``truth = {"style", "category", "face_mask" (True on ornament faces: twisted parts, shell
  carvings and crests, spindles, spade feet, pierced boards), "scale", "yaw_deg"}``.

``make_shape(style, category, rng, name, n_triangles=None)`` builds one shape (``generate``
passes triangle targets stratified within each style, so no style is denser on average);
numpy and scipy only, no Blender. Units before scaling are metres, front is -y.
"""
from __future__ import annotations

import functools
import math

import numpy as np
from scipy.spatial import Delaunay, cKDTree

from ..meshes import Mesh

STYLES = ("barleytwist", "shellcarved", "spindle", "spadefoot")
CATEGORIES = ("desk", "bench", "armchair", "bookcase", "sidetable")

TRI_RANGE = (3000, 10000)
SCALE_RANGE = (0.3, 300.0)

_X = np.array([1.0, 0.0, 0.0])
_Y = np.array([0.0, 1.0, 0.0])
_Z = np.array([0.0, 0.0, 1.0])


# ----------------------------------------------------------------------------- small helpers

def _unit(d) -> np.ndarray:
    d = np.asarray(d, np.float64)
    return d / np.linalg.norm(d)


def _perp_frame(d):
    """(e1, e2, d) right-handed with e1 x e2 = d."""
    d = _unit(d)
    a = _X if abs(d[0]) < 0.9 else _Y
    e1 = _unit(np.cross(a, d))
    e2 = np.cross(d, e1)
    return e1, e2, d


def _orient(V, F, want):
    """Flip triangles whose normal points against `want` (one direction per triangle)."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    nrm = np.cross(b - a, c - a)
    flip = np.einsum("ij,ij->i", nrm, want) < 0
    F = F.copy()
    F[flip] = F[flip][:, ::-1]
    return F


_LIBM_POW = np.frompyfunc(math.pow, 2, 1)


def _pow(x, e: float) -> np.ndarray:
    """x ** e by the C library's pow rather than numpy's, whose AVX-512 kernel rounds some last
    bits otherwise than other processors do: enough to turn a tessellation count of one of the
    benchmark's 120 shapes, so machines with and without AVX-512 drew another shape."""
    return np.asarray(_LIBM_POW(np.asarray(x, np.float64), float(e)), np.float64)


def _smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


# ----------------------------------------------------------------------------- blocks (boxes)

class _Block:
    """A box (optionally tapered along its local z) with its own frame; faces are grids.

    Local point (u, v, w) in [-1, 1]^3 maps to x = u*hx*(1+(tx-1)s), y = v*hy*(1+(ty-1)s),
    z = w*hz with s = (w+1)/2, then world = centre + axes @ (x, y, z)."""

    def __init__(self, centre, half, axes=None, taper=(1.0, 1.0)):
        self.c = np.asarray(centre, np.float64)
        self.h = np.asarray(half, np.float64)
        self.R = np.eye(3) if axes is None else np.asarray(axes, np.float64)
        self.t = np.asarray(taper, np.float64)

    def face_sizes(self):
        """(6, 2) approximate edge lengths of each face's two grid directions, in face order."""
        hx, hy, hz = self.h
        tx, ty = self.t
        mx, my = hx * (1 + tx) / 2, hy * (1 + ty) / 2
        out = []
        for a in range(3):
            for s in (1, -1):
                if a == 0:
                    out.append((2 * my, 2 * hz))
                elif a == 1:
                    out.append((2 * hz, 2 * mx))
                else:
                    f = (tx, ty) if s == 1 else (1.0, 1.0)
                    out.append((2 * hx * f[0], 2 * hy * f[1]))
        return np.asarray(out)

    def _map(self, L):
        s = (L[..., 2] + 1) / 2
        x = L[..., 0] * self.h[0] * (1 + (self.t[0] - 1) * s)
        y = L[..., 1] * self.h[1] * (1 + (self.t[1] - 1) * s)
        z = L[..., 2] * self.h[2]
        return self.c + np.stack([x, y, z], -1) @ self.R.T

    def build(self, subs=None):
        Ls, Fs, off, k = [], [], 0, 0
        for a in range(3):
            b, c = (a + 1) % 3, (a + 2) % 3
            for s in (1, -1):
                nb, nc = (1, 1) if subs is None else subs[k]
                k += 1
                PQ, Fpos, Fneg = _grid_template(int(nb), int(nc))
                L = np.empty((len(PQ), 3))
                L[:, a] = s
                L[:, b] = PQ[:, 0]
                L[:, c] = PQ[:, 1]
                Ls.append(L)
                Fs.append((Fpos if s > 0 else Fneg) + off)
                off += len(L)
        return self._map(np.concatenate(Ls)), np.concatenate(Fs)


@functools.lru_cache(maxsize=8192)
def _grid_template(nb, nc):
    """Parameter grid (in [-1, 1]^2) and its triangles, wound +, and wound -."""
    P, Q = np.meshgrid(np.linspace(-1, 1, nb + 1), np.linspace(-1, 1, nc + 1), indexing="ij")
    i, j = np.meshgrid(np.arange(nb), np.arange(nc), indexing="ij")
    i, j = i.ravel(), j.ravel()
    v00, v10 = i * (nc + 1) + j, (i + 1) * (nc + 1) + j
    v11, v01 = (i + 1) * (nc + 1) + j + 1, i * (nc + 1) + j + 1
    F = np.concatenate([np.stack([v00, v10, v11], 1), np.stack([v00, v11, v01], 1)])
    PQ = np.stack([P.ravel(), Q.ravel()], 1)
    for arr in (PQ, F):
        arr.setflags(write=False)
    Fn = np.ascontiguousarray(F[:, ::-1])
    Fn.setflags(write=False)
    return PQ, F, Fn


def _beam_axes(d):
    """Axes for a beam along d: local z = d, local x horizontal when possible."""
    d = _unit(d)
    if abs(d[2]) > 0.95:
        ex = _unit(_X - d * d[0])
    else:
        ex = _unit(np.cross(_Z, d))
    ey = np.cross(d, ex)
    return np.stack([ex, ey, d], 1)


# ----------------------------------------------------------------------------- tubes

def _tube(p0, p1, theta, t, radius, phi=None, caps=True):
    """Tube from p0 to p1: rings at fractions t (nt,), angles theta (nth,), radius (nt, nth),
    each ring rotated by phi (nt,). Outward winding, capped."""
    p0, p1 = np.asarray(p0, np.float64), np.asarray(p1, np.float64)
    e1, e2, d = _perp_frame(p1 - p0)
    L = np.linalg.norm(p1 - p0)
    nt, nth = len(t), len(theta)
    ang = theta[None, :] + (0 if phi is None else phi[:, None])
    radius = np.broadcast_to(radius, (nt, nth))
    P = (p0 + (t * L)[:, None, None] * d
         + radius[..., None] * (np.cos(ang)[..., None] * e1 + np.sin(ang)[..., None] * e2))
    V = P.reshape(-1, 3)
    j, i = np.meshgrid(np.arange(nt - 1), np.arange(nth), indexing="ij")
    j, i = j.ravel(), i.ravel()
    i1 = (i + 1) % nth
    a, b = j * nth + i, j * nth + i1
    c, e = (j + 1) * nth + i1, (j + 1) * nth + i
    F = [np.stack([a, b, c], 1), np.stack([a, c, e], 1)]
    if caps:
        n = len(V)
        V = np.concatenate([V, p0[None], p1[None]])
        ii = np.arange(nth)
        F.append(np.stack([np.full(nth, n), (ii + 1) % nth, ii], 1))
        top = (nt - 1) * nth
        F.append(np.stack([np.full(nth, n + 1), top + ii, top + (ii + 1) % nth], 1))
    return V, np.concatenate(F)


def _twist_tube(p0, p1, r, k, pitch, depth, hand, res):
    """A barley twist: k helical strands, radius r*(1 - depth*groove(k*theta - twist*z))."""
    L = float(np.linalg.norm(np.asarray(p1) - np.asarray(p0)))
    turns = L / pitch
    per = max(3, int(round(5 * res)))
    nth = k * per
    theta = np.linspace(0, 2 * np.pi, nth, endpoint=False)
    n_t = max(6, int(round(turns * 9 * res))) + 1
    t = np.linspace(0, 1, n_t)
    end = min(0.25, 1.5 * r / max(L, 1e-9))
    env = _smoothstep(np.minimum(t, 1 - t) / end)
    groove = _pow((1 - np.cos(k * theta)) / 2, 1.3)
    radius = r * (1 - depth * env[:, None] * groove[None, :])
    phi = hand * 2 * np.pi * turns * t
    return _tube(p0, p1, theta, t, radius, phi)


def _spindle(p0, p1, r, beads, bead_f, res):
    """A thin spindle with `beads` beads (bulges) and a slight swell."""
    nth = max(5, int(round(8 * res)))
    theta = np.linspace(0, 2 * np.pi, nth, endpoint=False)
    pos = {1: [0.5], 2: [0.22, 0.78], 3: [0.15, 0.5, 0.85]}[beads]
    w = 0.06
    ts, rs = [0.0, 1.0], [1.0, 1.0]
    for tb in pos:
        ts += [tb - w, tb, tb + w]
        rs += [1.0, bead_f, 1.0]
    if beads == 1 and res >= 0.8:
        ts += [0.25, 0.75]
        rs += [0.8, 0.8]
    o = np.argsort(ts, kind="stable")
    t = np.asarray(ts)[o]
    rad = r * np.asarray(rs)[o]
    return _tube(p0, p1, theta, t, rad[:, None])


def _cylinder(p0, p1, r, nth=12):
    theta = np.linspace(0, 2 * np.pi, nth, endpoint=False)
    return _tube(p0, p1, theta, np.array([0.0, 1.0]), np.full((2, 1), r))


# ----------------------------------------------------------------------------- boards (2D regions)

def _signed_area(P):
    x, y = P[:, 0], P[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


def _densify(P, step):
    P = np.asarray(P, np.float64)
    seg = np.roll(P, -1, 0) - P
    n = np.maximum(1, np.ceil(np.linalg.norm(seg, axis=1) / step).astype(int))
    idx = np.repeat(np.arange(len(P)), n)
    frac = (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)) / np.repeat(n, n)
    out = P[idx] + seg[idx] * frac[:, None]
    keep = np.linalg.norm(np.roll(out, -1, 0) - out, axis=1) > 1e-9
    return out[keep]


def _inside(pts, poly):
    lo, hi = poly.min(0), poly.max(0)
    box = np.all((pts >= lo) & (pts <= hi), axis=1)
    res = np.zeros(len(pts), bool)
    if box.any():
        res[box] = _inside_all(pts[box], poly)
    return res


def _inside_all(pts, poly):
    x, y = pts[:, 0:1], pts[:, 1:2]
    x0, y0 = poly[None, :, 0], poly[None, :, 1]
    x1, y1 = np.roll(poly[:, 0], -1)[None], np.roll(poly[:, 1], -1)[None]
    cond = (y0 > y) != (y1 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xi = x0 + (y - y0) * (x1 - x0) / np.where(y1 == y0, 1e-300, y1 - y0)
    return (np.sum(cond & (x < xi), axis=1) % 2) == 1


def _board(outer, holes, thick, origin, u, v, step, dense=None, coarse=False):
    """Extrude a 2D region (outer polygon minus holes) `thick` along n = u x v, centred on the
    plane through origin. Boundary sampled every `step`, interior points every `dense`."""
    u, v = _unit(u), _unit(v)
    n = np.cross(u, v)
    dense = dense or 3.0 * step
    if coarse:  # fewer vertices on finely sampled openings
        holes = [h[::2] if len(h) >= 16 else h for h in holes]
    loops = []
    o = np.asarray(outer, np.float64)
    loops.append(_densify(o if _signed_area(o) > 0 else o[::-1], step))
    for h in holes:
        h = np.asarray(h, np.float64)
        loops.append(_densify(h if _signed_area(h) < 0 else h[::-1], step))
    B = np.concatenate(loops)

    def in_region(p):
        m = _inside(p, loops[0])
        for h in loops[1:]:
            m &= ~_inside(p, h)
        return m

    lo, hi = B.min(0), B.max(0)
    gy = np.arange(lo[1] + dense / 2, hi[1], dense * 0.866)
    cand = []
    for r_i, yy in enumerate(gy):
        xs = np.arange(lo[0] + dense * (0.5 + 0.5 * (r_i % 2)), hi[0], dense)
        cand.append(np.stack([xs, np.full_like(xs, yy)], 1))
    cand = np.concatenate(cand) if cand else np.zeros((0, 2))
    if len(cand):
        cand = cand[in_region(cand)]
        if len(cand):
            dist = cKDTree(B).query(cand)[0]
            cand = cand[dist > 0.7 * dense]
    P = np.concatenate([B, cand])
    tri = Delaunay(P).simplices
    cen = P[tri].mean(1)
    tri = tri[in_region(cen)]
    a, b, c = P[tri[:, 0]], P[tri[:, 1]], P[tri[:, 2]]
    cr = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]
    tri = np.where(cr[:, None] < 0, tri[:, ::-1], tri)
    e2 = (np.sum((b - a) ** 2, 1) + np.sum((c - b) ** 2, 1) + np.sum((a - c) ** 2, 1))
    tri = tri[np.abs(cr) * 2 > 0.01 * e2]
    origin = np.asarray(origin, np.float64)
    flat = origin + P[:, 0:1] * u + P[:, 1:2] * v
    front, back = flat + n * thick / 2, flat - n * thick / 2
    V = np.concatenate([front, back])
    m = len(P)
    F = [tri, tri[:, ::-1] + m]
    off = 0
    for lp in loops:
        k = len(lp)
        i = np.arange(k) + off
        i1 = (np.arange(k) + 1) % k + off
        F.append(np.stack([i + m, i1 + m, i1], 1))
        F.append(np.stack([i + m, i1, i], 1))
        off += k
    return V, np.concatenate(F)


def _ellipse(cx, cy, rx, ry, rot=0.0, n=28):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x, y = rx * np.cos(a), ry * np.sin(a)
    c, s = np.cos(rot), np.sin(rot)
    return np.stack([cx + c * x - s * y, cy + s * x + c * y], 1)


def _splat_outline(W, H, crown):
    xs = np.linspace(W / 2, -W / 2, 25)
    top = H - crown * H * (2 * xs / W) ** 2
    return np.concatenate([[[-W / 2, 0.0], [W / 2, 0.0]], np.stack([xs, top], 1)])


def _pierce_pattern(kind, W, H, rng):
    """Holes (list of polygons) inside a W x H board with its bottom centre at (0, 0)."""
    holes = []
    m = min(W, H)
    if kind == "wheel":
        R = min(0.40 * W, 0.36 * H)
        cy = H * 0.52
        n = int(rng.integers(5, 9))
        r1, r2 = R * rng.uniform(0.26, 0.34), R
        sw = R * rng.uniform(0.07, 0.1)
        a0 = rng.uniform(0, 2 * np.pi)
        for i in range(n):
            ac, half = a0 + 2 * np.pi * i / n, np.pi / n
            ai = np.linspace(ac - half + sw / r1, ac + half - sw / r1, 5)
            ao = np.linspace(ac + half - sw / r2, ac - half + sw / r2, 9)
            pts = np.concatenate([np.stack([r1 * np.cos(ai), r1 * np.sin(ai)], 1),
                                  np.stack([r2 * np.cos(ao), r2 * np.sin(ao)], 1)])
            holes.append(pts + [0, cy])
        rest = (cy - R) - 0.1 * m
        if rest > 0.12 * m:
            holes.append(_ellipse(0, 0.05 * m + rest / 2 + 0.05 * m, 0.12 * W, rest * 0.38, n=20))
    elif kind == "vase":
        y0, y1 = 0.1 * H, 0.88 * H
        s = np.linspace(0, 1, 25)
        y = y0 + (y1 - y0) * s
        f = W * (0.07 + 0.13 * _pow(np.sin(np.pi * np.clip(s * 1.15, 0, 1)), 1.5)
                 + 0.06 * np.clip((s - 0.8) / 0.2, 0, 1))
        avail = W / 2 - 0.09 * W - f
        w = avail * _pow(np.sin(np.pi * s), 0.7)
        inner = -f
        outer_e = -f - w
        left = np.concatenate([np.stack([inner, y], 1), np.stack([outer_e[::-1], y[::-1]], 1)[1:-1]])
        holes.append(left)
        holes.append(left * [-1, 1])
        holes.append(_ellipse(0, y0 + 0.42 * (y1 - y0), 0.06 * W, 0.1 * H, n=20))
    else:  # "ovals"
        holes.append(_ellipse(0, 0.5 * H, 0.08 * W, 0.3 * H))
        tilt = rng.uniform(0.25, 0.45)
        for sx in (-1, 1):
            for sy in (-1, 1):
                holes.append(_ellipse(sx * 0.27 * W, 0.5 * H + sy * 0.2 * H,
                                      0.07 * W, 0.13 * H, rot=-sx * sy * tilt, n=22))
    return holes


def _strip_pattern(L, h, rng, kind=None):
    """Row of openings along a long strip of length L (centred on x=0) and height h."""
    kind = kind or rng.choice(["circle", "lozenge", "oval"])
    n = max(2, int(L / (h * 1.5)))
    pitch = L / n
    holes = []
    for i in range(n):
        cx = -L / 2 + pitch * (i + 0.5)
        if kind == "circle":
            holes.append(_ellipse(cx, h / 2, 0.3 * min(h, pitch), 0.3 * min(h, pitch), n=18))
        elif kind == "lozenge":
            a, b = 0.36 * pitch, 0.34 * h
            holes.append(np.array([[cx, h / 2 - b], [cx + a, h / 2], [cx, h / 2 + b], [cx - a, h / 2]]))
        else:
            holes.append(_ellipse(cx, h / 2, 0.36 * pitch, 0.25 * h, n=18))
    return holes


# ----------------------------------------------------------------------------- shells

def _fan_radius(phi, n_ribs, scallop):
    rib = _pow(np.abs(np.sin(n_ribs * phi)), 0.6)
    return (1 - scallop) + scallop * rib, rib


def _shell_relief(o, u, v, R, n_ribs, relief, scallop, res):
    """A half-disc of radial ribs in relief, base on the plane through o, opening along v."""
    o = np.asarray(o, np.float64)
    u, v = _unit(u), _unit(v)
    n = np.cross(u, v)
    sp = max(2, int(round(4 * res)))
    phi = np.linspace(0, np.pi, n_ribs * sp + 1)
    nr = max(2, int(round(4 * res)))
    r_in = 0.2
    rr = np.linspace(r_in, 1, nr + 1)
    rim, rib = _fan_radius(phi, n_ribs, scallop)
    H = relief * R
    h = H * (0.3 + 0.7 * rib)[None, :] * (1.0 - 0.45 * rr[:, None] ** 2)
    rad = R * rr[:, None] * rim[None, :]
    dirs = np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * v
    P = o + rad[..., None] * dirs[None] + h[..., None] * n
    nr1, nph = P.shape[0], P.shape[1]
    V = [P.reshape(-1, 3)]
    j, i = np.meshgrid(np.arange(nr1 - 1), np.arange(nph - 1), indexing="ij")
    j, i = j.ravel(), i.ravel()
    a, b, c, d = j * nph + i, (j + 1) * nph + i, (j + 1) * nph + i + 1, j * nph + i + 1
    F = [np.stack([a, b, c], 1), np.stack([a, c, d], 1)]
    want = [np.tile(n, (2 * len(a), 1))]
    base = nr1 * nph
    # hub: half disc fan around the centre
    hub = o + n * H * 1.05
    V.append(hub[None])
    ii = np.arange(nph - 1)
    F.append(np.stack([np.full(nph - 1, base), ii, ii + 1], 1))
    want.append(np.tile(n, (nph - 1, 1)))
    base += 1
    # rim wall down to the base plane
    top = P[-1]
    bot = top - h[-1][:, None] * n
    V.append(bot)
    ti = (nr1 - 1) * nph + ii
    bi = base + ii
    F += [np.stack([ti, bi, bi + 1], 1), np.stack([ti, bi + 1, ti + 1], 1)]
    mid = (top[:-1] + top[1:]) / 2 - o
    want += [mid, mid]
    base += nph
    # straight base wall along the diameter: phi = pi side (outer->inner), hub, phi = 0 side
    line_idx = list((np.arange(nr1)[::-1]) * nph + (nph - 1)) + [nr1 * nph] + list(np.arange(nr1) * nph)
    allV = np.concatenate(V)
    lp = allV[line_idx]
    lb = lp - np.outer(lp @ n - o @ n, n)
    V.append(lb)
    k = len(line_idx)
    q = np.arange(k - 1)
    ta, tb = np.asarray(line_idx)[q], np.asarray(line_idx)[q + 1]
    F += [np.stack([ta, base + q, base + q + 1], 1), np.stack([ta, base + q + 1, tb], 1)]
    want += [np.tile(-v, (k - 1, 1))] * 2
    V = np.concatenate(V)
    F = np.concatenate(F)
    return V, _orient(V, F, np.concatenate(want))


def _fan_outline(Rx, Ry, n_ribs, scallop, n=None):
    n = n or n_ribs * 4 + 1
    phi = np.linspace(0, np.pi, n)
    rim, _ = _fan_radius(phi, n_ribs, scallop)
    return np.stack([Rx * rim * np.cos(phi), Ry * rim * np.sin(phi)], 1)


# ----------------------------------------------------------------------------- the builder

class _Builder:
    """Collects parts: plain blocks (padded later), fixed meshes, and res-scaled ornament."""

    def __init__(self, style, rng):
        self.style = style
        self.rng = rng
        self.blocks = []          # (_Block, ornament)
        self.parts = []           # (fn(res) -> (V, F), ornament)
        self.p = _style_params(style, rng)

    # plain geometry
    def box(self, lo, hi, orn=False):
        lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
        lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
        self.blocks.append((_Block((lo + hi) / 2, (hi - lo) / 2), orn))

    def beam(self, p0, p1, hx, hy, orn=False, taper=(1.0, 1.0)):
        p0, p1 = np.asarray(p0, np.float64), np.asarray(p1, np.float64)
        L = np.linalg.norm(p1 - p0)
        self.blocks.append((_Block((p0 + p1) / 2, (hx, hy, L / 2), _beam_axes(p1 - p0), taper), orn))

    def add(self, fn, orn=True):
        self.parts.append((fn, orn))

    # ---- ornament primitives
    def twist(self, p0, p1, r):
        p = self.p
        self.add(lambda res, p0=np.asarray(p0, float), p1=np.asarray(p1, float):
                 _twist_tube(p0, p1, r, p["k"], max(p["pitch"] * 2 * r, np.linalg.norm(p1 - p0) / 6.5),
                             p["depth"], p["hand"], res))

    def spindles(self, a, b, z0, z1, spacing=None, r=None):
        """Row of vertical spindles between 2D points a and b, from z0 to z1."""
        p = self.p
        a, b = np.asarray(a, float), np.asarray(b, float)
        L = np.linalg.norm(b - a)
        spacing = spacing or p["spacing"]
        r = r or spacing * p["rs"]
        n = max(2, int(round(L / spacing)))
        for i in range(n):
            q = a + (b - a) * (i + 0.5) / n
            self.add(lambda res, q=q: _spindle((q[0], q[1], z0), (q[0], q[1], z1), r,
                                                 p["beads"], p["bead_f"], res))

    def gallery(self, a, b, z0, z1, depth, rail_h, bottom=True, top=True):
        """Spindles between a top rail and a bottom rail (rails plain)."""
        a, b = np.asarray(a, float), np.asarray(b, float)
        zb, zt = z0, z1
        if bottom:
            self._hrail(a, b, z0, z0 + rail_h, depth)
            zb = z0 + rail_h
        if top:
            self._hrail(a, b, z1 - rail_h, z1, depth)
            zt = z1 - rail_h
        self.spindles(a, b, zb, zt)

    def _hrail(self, a, b, za, zb, depth):
        d = _unit(np.append(b - a, 0.0))
        s = np.append(np.array([-d[1], d[0]]) * depth / 2, 0)
        P = [np.append(a, za) - s, np.append(b, za) - s, np.append(a, zb) + s, np.append(b, zb) + s]
        P = np.asarray(P)
        self.box(P.min(0), P.max(0))

    def board(self, outer, holes, thick, origin, u, v, step, orn=True):
        self.add(lambda res: _board(outer, holes, thick, origin, u, v, step / res, coarse=res < 0.8), orn)

    def shell(self, o, u, v, R, backing=0.01):
        """Shell carving with its fan-shaped backing; o on the carrier's outer face,
        u along the flat edge, v the fan direction; the carving stands out along u x v."""
        p = self.p
        o, u, v = np.asarray(o, float), _unit(u), _unit(v)
        n = np.cross(u, v)
        outline = _fan_outline(R * 1.07, R * 1.07, p["ribs"], p["scallop"] * 0.6)
        self.add(lambda res: _board(outline, [], backing, o + n * backing / 2, u, v, R * 0.09 / res))
        self.add(lambda res: _shell_relief(o + n * backing, u, v, R, p["ribs"], p["relief"],
                                           p["scallop"], res))

    def crest(self, o, u, v, W, H, thick):
        """Scalloped fan-shaped crest board (bottom centre o) with a shell carving on it."""
        p = self.p
        outline = _fan_outline(W / 2, H, p["crest_lobes"], p["scallop"] * 1.3, n=p["crest_lobes"] * 6 + 1)
        o, u, v = np.asarray(o, float), _unit(u), _unit(v)
        n = np.cross(u, v)
        self.add(lambda res: _board(outline, [], thick, o, u, v, min(W, H) * 0.06 / res))
        R = min(W * 0.3, H * 0.75)
        self.shell(o + n * thick / 2 + v * H * 0.04, u, v, R, backing=thick * 0.3)

    # ---- style kit
    def leg(self, x, y, z0, z1, th, joints=()):
        st, p = self.style, self.p
        if st == "barleytwist":
            cuts = sorted([(max(z0, a), min(z1, b)) for a, b in joints])
            foot = min(0.12 * (z1 - z0), 1.2 * th)
            cuts = [(z0, z0 + foot)] + cuts
            if not cuts or cuts[-1][1] < z1 - 1e-9:
                cuts.append((z1 - min(0.8 * th, 0.08 * (z1 - z0)), z1))
            for a, b in cuts:
                self.beam((x, y, a), (x, y, b), th / 2, th / 2)
            for (a0, b0), (a1, b1) in zip(cuts[:-1], cuts[1:]):
                if a1 - b0 > 2.5 * th:
                    self.twist((x, y, b0), (x, y, a1), th * 0.6)
                elif a1 > b0:
                    self.beam((x, y, b0), (x, y, a1), th / 2, th / 2)
        elif st == "spadefoot":
            fh = min(p["foot_h"] * (z1 - z0), 0.12)
            tp = p["taper"]
            self.beam((x, y, z0 + fh), (x, y, z1), th / 2 * tp, th / 2 * tp, taper=(1 / tp, 1 / tp))
            ftop = th / 2 * tp * p["foot_w"]
            self.beam((x, y, z0), (x, y, z0 + fh), ftop * 0.6, ftop * 0.6, orn=True,
                      taper=(1 / 0.6, 1 / 0.6))
        elif st == "spindle" and p["round_legs"]:
            self.add(lambda res: _cylinder((x, y, z0), (x, y, z1), th / 2, 12), orn=False)
        else:
            self.beam((x, y, z0), (x, y, z1), th / 2, th / 2)

    def post(self, x, y, z0, z1, th):
        """A vertical support that does not reach the floor (arm support, bookcase column)."""
        if self.style == "barleytwist" and z1 - z0 > 3 * th:
            cap = min(th, 0.2 * (z1 - z0))
            self.beam((x, y, z0), (x, y, z0 + cap), th / 2, th / 2)
            self.beam((x, y, z1 - cap), (x, y, z1), th / 2, th / 2)
            self.twist((x, y, z0 + cap), (x, y, z1 - cap), th * 0.55)
        elif self.style == "spindle" and self.p["round_legs"]:
            self.add(lambda res: _cylinder((x, y, z0), (x, y, z1), th / 2, 12), orn=False)
        else:
            self.beam((x, y, z0), (x, y, z1), th / 2, th / 2)

    def rail(self, p0, p1, w, h, twist_ok=True):
        """A horizontal stretcher or rail."""
        if self.style == "barleytwist" and twist_ok and np.linalg.norm(np.subtract(p1, p0)) > 4 * max(w, h):
            self.twist(p0, p1, max(w, h) * 0.55)
        else:
            self.beam(p0, p1, w / 2, h / 2)

    def apron(self, a, b, z_top, h, t, out, shell=True, pierce=True, gallery=True):
        """Apron (seat rail / frieze) under a top, centre line a-b (2D), outward normal out (2D)."""
        st, p = self.style, self.p
        a, b = np.asarray(a, float), np.asarray(b, float)
        out = _unit(np.append(out, 0.0))
        L = np.linalg.norm(b - a)
        u = _unit(np.append(b - a, 0.0))
        mid = np.append((a + b) / 2, 0.0)
        if st == "spindle" and gallery:
            hg = h * p["gallery_f"]
            self.gallery(a, b, z_top - hg, z_top, t, max(0.25 * h, 0.018))
            return
        if st == "spadefoot" and pierce:
            holes = _strip_pattern(L * 0.92, h * 0.8, self.rng)
            holes = [hh + [0, h * 0.1] for hh in holes]
            outer = np.array([[-L / 2, 0], [L / 2, 0], [L / 2, h], [-L / 2, h]])
            self.board(outer, holes, t, mid + _Z * (z_top - h), u, _Z, h * 0.1)
            return
        self.beam((*a, z_top - h / 2), (*b, z_top - h / 2), t / 2, h / 2)
        if st == "shellcarved" and shell:
            R = min(0.42 * L, max(h * p["drop_f"], min(0.2 * L, 0.16)))
            # flat edge near the apron top, fan hanging down: u' x (-z) must equal out
            uu = np.cross(-_Z, out)  # (uu, -z, out) right-handed: the carving faces out
            n = max(1, int(L / (4.2 * R)))
            for i in range(n):
                c = np.append(a + (b - a) * (i + 0.5) / n, 0.0)
                self.shell(c + out * t / 2 + _Z * (z_top - 0.12 * h), uu, -_Z, R)

    def back(self, x0, x1, y, z0, z1, rh, depth):
        """Fill a chair/bench back between posts at x0 and x1 (plane y), seat z0 to post top z1."""
        st, p = self.style, self.p
        W, Hb = x1 - x0, z1 - z0
        self.box((x0, y - depth / 2, z0), (x1, y + depth / 2, z0 + rh))          # lower back rail
        if st == "barleytwist":
            self.rail((x0, y, z1 - rh / 2), (x1, y, z1 - rh / 2), depth, rh)
            n = int(np.clip(round(W / 0.15), 2, 6))
            r = min(0.45 * W / n / 2 + 0.008, 0.024)
            for i in range(n):
                x = x0 + W * (i + 0.5) / n
                self.twist((x, y, z0 + rh), (x, y, z1 - rh), r)
        elif st == "shellcarved":
            self.box((x0, y - depth / 2, z1 - rh), (x1, y + depth / 2, z1))
            sw = W * self.p["splat_f"]
            self.box((-sw / 2 + (x0 + x1) / 2, y - 0.01, z0 + rh), (sw / 2 + (x0 + x1) / 2, y + 0.01, z1 - rh))
            self.crest(((x0 + x1) / 2, y, z1), _X, _Z, W * p["crest_w"], max(0.07, Hb * p["crest_h"]), depth)
            if Hb > 4 * rh:
                self.shell(((x0 + x1) / 2, y - 0.01, z0 + rh), _X, _Z, min(sw * 0.45, (Hb - 2 * rh) * 0.4))
        elif st == "spindle":
            self.box((x0, y - depth / 2, z1 - rh), (x1, y + depth / 2, z1))
            a, b = (x0, y), (x1, y)
            if p["two_tier"] and Hb > 0.3:
                zm = z0 + rh + (Hb - 2 * rh) * 0.55
                self.box((x0, y - depth / 2, zm - rh / 2), (x1, y + depth / 2, zm + rh / 2))
                self.spindles(a, b, z0 + rh, zm - rh / 2)
                self.spindles(a, b, zm + rh / 2, z1 - rh)
            else:
                self.spindles(a, b, z0 + rh, z1 - rh)
        else:  # spadefoot: pierced splats
            self.box((x0, y - depth / 2, z1 - rh), (x1, y + depth / 2, z1))
            n = max(1, int(round(W / 0.42)))
            sw = min(0.36, W / n * 0.78)
            sh = Hb - 2 * rh
            for i in range(n):
                xc = x0 + W * (i + 0.5) / n
                outer = _splat_outline(sw, sh, p["crown"])
                holes = _pierce_pattern(p["pattern"], sw, sh * (1 - p["crown"]), self.rng)
                self.board(outer, holes, min(depth, 0.022), (xc, y, z0 + rh), _X, _Z, min(sw, sh) * 0.04)

    def top_ornament_side(self, a, c, z, h, depth):
        """A pierced return board standing on a top between 2D points a and c."""
        a, c = np.asarray(a, float), np.asarray(c, float)
        L = float(np.linalg.norm(c - a))
        holes = [hh + [0, h * 0.1] for hh in _strip_pattern(L * 0.85, h * 0.75, self.rng)]
        outer = np.array([[-L / 2, 0], [L / 2, 0], [L / 2, h], [-L / 2, h]])
        u = _unit(np.append(c - a, 0.0))
        self.board(outer, holes, depth, np.append((a + c) / 2, z), u, _Z, h * 0.09)

    def top_ornament(self, x0, x1, y, z, h, depth, front_out=(0.0, -1.0), wide=False):
        """Ornament standing on a top along its back (or front) edge, from x0 to x1 at plane y."""
        st, p = self.style, self.p
        W = x1 - x0
        xc = (x0 + x1) / 2
        if st == "barleytwist":
            pw = max(0.03, h * 0.3)
            self.box((x0, y - depth / 2, z), (x0 + pw, y + depth / 2, z + h))
            self.box((x1 - pw, y - depth / 2, z), (x1, y + depth / 2, z + h))
            self.box((x0, y - 0.006, z), (x1, y + 0.006, z + h * 0.35))
            self.twist((x0 + pw, y, z + h * 0.72), (x1 - pw, y, z + h * 0.72), min(0.4 * h, 0.03))
        elif st == "shellcarved":
            u = _X if front_out[1] < 0 else -_X
            if wide:
                self.crest((xc, y, z), u, _Z, W * max(p["crest_w"], 0.8), h * 1.4, depth)
            else:
                self.crest((xc, y, z), u, _Z, W * p["crest_w"], h, depth)
        elif st == "spindle":
            self.gallery((x0, y), (x1, y), z, z + h, depth, max(0.015, h * 0.15), bottom=False)
        else:
            L = W
            holes = _strip_pattern(L * 0.9, h * 0.75, self.rng)
            holes = [hh + [0, h * 0.08] for hh in holes]
            xs = np.linspace(L / 2, -L / 2, 21)
            top = h - p["crown"] * 1.5 * h * (2 * xs / L) ** 2
            outer = np.concatenate([[[-L / 2, 0], [L / 2, 0]], np.stack([xs, top], 1)])
            self.board(outer, holes, depth, (xc, y, z), _X, _Z, h * 0.09)


def _style_params(style, r):
    p = {"side_orn": bool(r.random() < 0.5) or style == "spindle"}
    if style == "barleytwist":
        p.update(k=int(r.choice([2, 3])), depth=r.uniform(0.3, 0.45), pitch=r.uniform(2.2, 3.4),
                 hand=float(r.choice([-1, 1])))
    elif style == "shellcarved":
        p.update(ribs=int(r.integers(8, 14)), relief=r.uniform(0.14, 0.22),
                 scallop=r.uniform(0.07, 0.12), drop_f=r.uniform(1.1, 1.6),
                 crest_lobes=int(r.integers(5, 10)), splat_f=r.uniform(0.3, 0.5),
                 crest_w=r.uniform(0.55, 0.95), crest_h=r.uniform(0.16, 0.3))
    elif style == "spindle":
        sp = r.uniform(0.05, 0.085)
        p.update(spacing=sp, rs=r.uniform(0.17, 0.24), beads=int(r.integers(1, 3)),
                 bead_f=r.uniform(1.4, 1.8), round_legs=bool(r.random() < 0.5),
                 two_tier=bool(r.random() < 0.4), gallery_f=r.uniform(1.2, 1.8))
    elif style == "spadefoot":
        p.update(taper=r.uniform(0.55, 0.72), foot_h=r.uniform(0.1, 0.16), foot_w=r.uniform(1.25, 1.45),
                 pattern=str(r.choice(["wheel", "vase", "ovals"])), crown=r.uniform(0.0, 0.12))
    return p


# ----------------------------------------------------------------------------- categories
# Each category draws ALL its proportions from `r` (a stream that never sees the style) before
# handing parts to the builder's style kit.

def _four_aprons(b, lx, ly, th, at, zt, ah, plain_front=False):
    fy = ly + th / 2 - at / 2
    fx = lx + th / 2 - at / 2
    b.apron((-lx, -fy), (lx, -fy), zt, ah, at, (0, -1), shell=not plain_front,
            pierce=not plain_front, gallery=not plain_front)
    b.apron((-lx, fy), (lx, fy), zt, ah, at, (0, 1))
    side = b.p.get("side_orn", True) or plain_front
    b.apron((-fx, -ly), (-fx, ly), zt, ah, at, (-1, 0), shell=side, pierce=side, gallery=side)
    b.apron((fx, -ly), (fx, ly), zt, ah, at, (1, 0), shell=side, pierce=side, gallery=side)
    return fy


def _drawers(b, x0, x1, y_face, z0, z1, n):
    """n drawer fronts side by side on a face at y_face (facing -y), with knobs."""
    W = (x1 - x0) / n
    for i in range(n):
        a, c = x0 + W * i + 0.006, x0 + W * (i + 1) - 0.006
        b.box((a, y_face - 0.014, z0), (c, y_face, z1))
        xm, zm = (a + c) / 2, (z0 + z1) / 2
        k = min(0.012, (z1 - z0) * 0.15)
        b.box((xm - k, y_face - 0.014 - 2 * k, zm - k), (xm + k, y_face - 0.014, zm + k))
        if b.style == "shellcarved" and z1 - z0 > 0.06:
            b.shell((xm, y_face - 0.014, z0 + 0.004), _X, _Z, min((c - a) * 0.35, (z1 - z0) * 0.42),
                    backing=0.004)


def _sidetable(b, r):
    W = r.uniform(0.4, 0.75)
    D = W * r.uniform(0.6, 1.0)
    H = r.uniform(0.5, 0.78)
    tt, over = r.uniform(0.02, 0.04), r.uniform(0.01, 0.05)
    th, ah, at = r.uniform(0.03, 0.055), r.uniform(0.07, 0.14), r.uniform(0.016, 0.024)
    drawer, shelf = r.random() < 0.5, r.random() < 0.45
    stretch = (not shelf) and r.random() < 0.6
    sz = r.uniform(0.12, 0.28) * H
    zt = H - tt
    b.box((-W / 2, -D / 2, zt), (W / 2, D / 2, H))
    lx, ly = W / 2 - over - th / 2, D / 2 - over - th / 2
    joints = [(zt - ah, zt)] + ([(sz - th / 2, sz + th / 2)] if (shelf or stretch) else [])
    for sx in (-1, 1):
        for sy in (-1, 1):
            b.leg(sx * lx, sy * ly, 0, zt, th, joints)
    fy = _four_aprons(b, lx, ly, th, at, zt, ah, plain_front=drawer)
    if drawer:
        _drawers(b, -lx * 0.75, lx * 0.75, -fy - at / 2, zt - ah * 0.9, zt - ah * 0.1, 1)
    if shelf:
        b.box((-lx - th / 2, -ly - th / 2, sz - 0.01), (lx + th / 2, ly + th / 2, sz + 0.01))
        if b.style == "spindle":
            g = min(0.08, 0.3 * (zt - ah - sz))
            b.gallery((-lx, -ly), (lx, -ly), sz, sz + g, 0.015, 0.012, bottom=False)
            b.gallery((-lx, ly), (lx, ly), sz, sz + g, 0.015, 0.012, bottom=False)
    if stretch:
        w = th * 0.6
        for sx in (-1, 1):
            b.rail((sx * lx, -ly, sz), (sx * lx, ly, sz), w, w)
        b.rail((-lx, 0, sz), (lx, 0, sz), w, w)


def _desk(b, r):
    W, D, H = r.uniform(1.0, 1.7), r.uniform(0.5, 0.8), r.uniform(0.72, 0.79)
    tt, over = r.uniform(0.025, 0.045), r.uniform(0.01, 0.04)
    th, ah, at = r.uniform(0.04, 0.065), r.uniform(0.1, 0.17), r.uniform(0.018, 0.025)
    nd = int(r.integers(0, 4))
    stretch, sz = r.random() < 0.5, r.uniform(0.1, 0.2)
    sup, hs = r.random() < 0.7, r.uniform(0.12, 0.28)
    zt = H - tt
    b.box((-W / 2, -D / 2, zt), (W / 2, D / 2, H))
    lx, ly = W / 2 - over - th / 2, D / 2 - over - th / 2
    joints = [(zt - ah, zt)] + ([(sz - th / 2, sz + th / 2)] if stretch else [])
    for sx in (-1, 1):
        for sy in (-1, 1):
            b.leg(sx * lx, sy * ly, 0, zt, th, joints)
    fy = _four_aprons(b, lx, ly, th, at, zt, ah, plain_front=nd > 0)
    if nd:
        _drawers(b, -lx + th / 2, lx - th / 2, -fy - at / 2, zt - ah * 0.92, zt - ah * 0.08, nd)
    if stretch:
        w = th * 0.6
        for sx in (-1, 1):
            b.rail((sx * lx, -ly, sz), (sx * lx, ly, sz), w, w)
        b.rail((-lx, 0, sz), (lx, 0, sz), w, w)
    if sup:
        b.top_ornament(-W / 2 + 0.02, W / 2 - 0.02, D / 2 - 0.03, H, hs, 0.02)


def _seat_furniture(b, L, D, Hs, st, th, ah, at, over, six, back, hb, arms, ha, stretch, sz, aw):
    zs = Hs - st
    b.box((-L / 2, -D / 2, zs), (L / 2, D / 2, Hs))
    lx, ly = L / 2 - over - th / 2, D / 2 - over - th / 2
    xs = [-lx, lx] + ([0.0] if six else [])
    j = [(zs - ah, zs)] + ([(sz - th / 2, sz + th / 2)] if stretch else [])
    for x in xs:
        b.leg(x, -ly, 0, zs, th, j)
        top = Hs + hb if (back and x != 0.0) else zs
        b.leg(x, ly, 0, top, th, j + ([(zs - ah, Hs + 0.03)] if top > zs else []))
    _four_aprons(b, lx, ly, th, at, zs, ah)
    if back:
        b.back(-lx + th / 2, lx - th / 2, ly, Hs, Hs + hb, max(0.035, hb * 0.1), th * 0.7)
    if arms:
        za = Hs + ha
        for sx in (-1, 1):
            x = sx * lx
            b.post(x, -ly, Hs, za, th * 0.85)
            b.box((x - aw / 2, -ly - 0.04, za), (x + aw / 2, ly, za + 0.028))
            if b.style == "spindle":
                b.spindles((x, -ly + th), (x, ly - th), Hs, za)
    if stretch:
        w = th * 0.55
        for x in xs:
            b.rail((x, -ly, sz), (x, ly, sz), w, w)
        b.rail((-lx, 0, sz), (lx, 0, sz), w, w)


def _bench(b, r):
    L, D, Hs = r.uniform(0.9, 1.9), r.uniform(0.32, 0.55), r.uniform(0.4, 0.48)
    st, th = r.uniform(0.03, 0.06), r.uniform(0.035, 0.065)
    ah, at, over = r.uniform(0.06, 0.12), r.uniform(0.018, 0.025), r.uniform(0.0, 0.03)
    six = L > 1.45 and r.random() < 0.6
    back, hb = r.random() < 0.65, r.uniform(0.35, 0.6)
    arms, ha = r.random() < 0.4, r.uniform(0.18, 0.26)
    stretch, sz = r.random() < 0.6, r.uniform(0.1, 0.2)
    aw = r.uniform(0.05, 0.08)
    _seat_furniture(b, L, D, Hs, st, th, ah, at, over, six, back, hb, back and arms, ha, stretch, sz, aw)


def _armchair(b, r):
    W, D, Hs = r.uniform(0.5, 0.72), r.uniform(0.45, 0.6), r.uniform(0.4, 0.48)
    st, th = r.uniform(0.03, 0.07), r.uniform(0.035, 0.06)
    ah, at, over = r.uniform(0.05, 0.1), r.uniform(0.018, 0.025), r.uniform(0.0, 0.03)
    hb, ha = r.uniform(0.4, 0.65), r.uniform(0.18, 0.28)
    stretch, sz = r.random() < 0.6, r.uniform(0.1, 0.2)
    aw = r.uniform(0.05, 0.09)
    _seat_furniture(b, W, D, Hs, st, th, ah, at, over, False, True, hb, True, ha, stretch, sz, aw)


def _bookcase(b, r):
    W, D, Htot = r.uniform(0.6, 1.4), r.uniform(0.25, 0.45), r.uniform(0.9, 2.1)
    bt = r.uniform(0.016, 0.03)
    legs, lh, th, ph = r.random() < 0.55, r.uniform(0.1, 0.25), r.uniform(0.035, 0.06), r.uniform(0.05, 0.12)
    doors = r.random() < 0.45
    n_sh = int(r.integers(2, 7))
    top_h = r.uniform(0.14, 0.3)
    ov = r.uniform(0.0, 0.03)
    has_back = r.random() < 0.5
    frieze_h = r.uniform(0.05, 0.1)
    zb = lh if legs else ph
    n_sh = int(min(n_sh, max(1, (Htot - zb) // 0.24 - 1)))
    x_in = W / 2 - bt
    zs = np.linspace(zb + bt, Htot - bt, n_sh + 2)[1:-1]
    for sx in (-1, 1):
        if b.style == "spindle":  # spindled sides: stiles, rails and rows of spindles
            xo = sx * (W / 2 - bt / 2)
            sw = min(0.05, D * 0.18)
            b.box((sx * W / 2, -D / 2, zb), (sx * x_in, -D / 2 + sw, Htot - bt))
            b.box((sx * W / 2, D / 2 - sw, zb), (sx * x_in, D / 2, Htot - bt))
            levels = [zb] + [z for z in zs[1::2]] + [Htot - bt]
            rh = 0.04
            for za in levels:
                b.box((sx * W / 2, -D / 2 + sw, max(zb, za - rh / 2)), (sx * x_in, D / 2 - sw, min(Htot - bt, za + rh / 2)))
            for za, zb_ in zip(levels[:-1], levels[1:]):
                b.spindles((xo, -D / 2 + sw), (xo, D / 2 - sw), za + rh / 2, zb_ - rh / 2)
        else:
            b.box((sx * W / 2, -D / 2, zb), (sx * x_in, D / 2, Htot - bt))
    b.box((-W / 2 - ov, -D / 2 - ov, Htot - bt), (W / 2 + ov, D / 2, Htot))
    b.box((-x_in, -D / 2, zb), (x_in, D / 2, zb + bt))
    if has_back:
        b.box((-x_in, D / 2 - 0.01, zb + bt), (x_in, D / 2, Htot - bt))
    for z in zs:
        b.box((-x_in, -D / 2 + 0.005, z - bt / 2), (x_in, D / 2 - 0.01, z + bt / 2))
    if legs:
        lx, ly = W / 2 - th / 2, D / 2 - th / 2
        for sx in (-1, 1):
            for sy in (-1, 1):
                b.leg(sx * lx, sy * ly, 0, zb, th)
        ah = min(0.45 * lh, 0.09)
        b.apron((-lx, -ly), (lx, -ly), zb, ah, 0.02, (0, -1), gallery=False)
        if b.style == "barleytwist":
            b.rail((-lx, -ly, zb * 0.4), (lx, -ly, zb * 0.4), th * 0.6, th * 0.6)
    else:
        b.box((-W / 2 + 0.01, -D / 2 + 0.01, 0), (W / 2 - 0.01, D / 2, zb))
        if b.style == "shellcarved":
            b.shell((0, -D / 2 + 0.01, 0.005), _X, _Z, min(0.9 * zb, 0.3 * W), backing=0.005)
    fh = min(frieze_h, 0.3 * (Htot - bt - zs[-1]))
    b.apron((-x_in, -D / 2 + 0.01), (x_in, -D / 2 + 0.01), Htot - bt, fh, 0.02, (0, -1), gallery=False)
    for sx in (-1, 1):  # frieze returns on the outer faces of the sides
        b.apron((sx * (W / 2 + 0.01), -D / 2), (sx * (W / 2 + 0.01), D / 2), Htot - bt, fh, 0.02, (sx, 0),
                gallery=False)
    if doors:
        zd0, zd1 = zb + bt, zs[0] - bt / 2
        nd = 1 if W < 0.8 else 2
        dw = 2 * x_in / nd
        for i in range(nd):
            x0 = -x_in + dw * i + 0.003
            x1 = x0 + dw - 0.006
            yf = -D / 2 - 0.02
            if b.style == "spadefoot":
                w, h = x1 - x0, zd1 - zd0
                outer = np.array([[-w / 2, 0], [w / 2, 0], [w / 2, h], [-w / 2, h]])
                holes = _pierce_pattern(b.p["pattern"], w * 0.8, h * 0.8, b.rng)
                holes = [hh + [0, h * 0.1] for hh in holes]
                b.board(outer, holes, 0.02, ((x0 + x1) / 2, yf + 0.01, zd0), _X, _Z, min(w, h) * 0.035)
            else:
                b.box((x0, yf, zd0), (x1, yf + 0.02, zd1))
                if b.style == "shellcarved":
                    b.shell(((x0 + x1) / 2, yf, zd0 + (zd1 - zd0) * 0.3), _X, _Z,
                            min(0.35 * (x1 - x0), 0.35 * (zd1 - zd0)), backing=0.005)
    if b.style == "barleytwist":
        rc = 0.03 + 0.015 * (W - 0.6)
        for sy in ((-1, 1) if not has_back else (-1,)):
            yc = sy * (D / 2 + rc * 0.6)
            for sx in (-1, 1):
                b.post(sx * (W / 2 - rc * 0.7), yc, zb + bt, Htot - bt, 2 * rc)
            for zr in (Htot - bt - rc * 0.8, zb + bt + rc * 0.8):
                b.rail((-W / 2 + 2 * rc, yc - sy * rc * 0.2, zr), (W / 2 - 2 * rc, yc - sy * rc * 0.2, zr),
                       rc * 1.3, rc * 1.3)
    else:
        y = -D / 2 + 0.025
        b.top_ornament(-W / 2 + 0.02, W / 2 - 0.02, y, Htot, top_h, 0.02, wide=True)
        for sx in (-1, 1):  # returns along the sides
            a, c = (sx * (W / 2 - 0.02), y + 0.02), (sx * (W / 2 - 0.02), D / 2 - 0.01)
            if b.style == "spindle":
                b.gallery(a, c, Htot, Htot + top_h, 0.02, max(0.015, top_h * 0.15), bottom=False)
            elif b.style == "spadefoot":
                b.top_ornament_side(a, c, Htot, top_h * 0.7, 0.02)


_CATEGORY_BUILDERS = {"desk": _desk, "bench": _bench, "armchair": _armchair,
                      "bookcase": _bookcase, "sidetable": _sidetable}


# ----------------------------------------------------------------------------- assembly

def _pad_counts(sizes, avail):
    """Per-face grid (na, nb) at one density, the largest whose triangle total fits `avail`."""
    la, lb = np.maximum(sizes[:, 0], 1e-6), np.maximum(sizes[:, 1], 1e-6)

    def grids(rho):
        s = np.sqrt(rho)
        return np.maximum(1, np.round(la * s)).astype(int), np.maximum(1, np.round(lb * s)).astype(int)

    lo, hi = 0.0, 1e10
    if 2 * len(la) >= avail:
        return grids(0.0)
    for _ in range(50):
        mid = np.sqrt(max(lo, 1e-6) * hi)
        na, nb = grids(mid)
        if 2 * np.sum(na * nb) <= avail:
            lo = mid
        else:
            hi = mid
    na, nb = grids(lo)
    # many equal faces cross a rounding step together: spend what is left face by face
    rem = int(avail - 2 * np.sum(na * nb))
    # stable: numpy's AVX-512 argsort orders equal keys otherwise than other processors do,
    # which gave 90 of the benchmark's 120 shapes other tessellations on other machines
    order = np.argsort(-(la * lb), kind="stable")
    for _ in range(4):
        for i in order:
            if rem < 2 * min(na[i], nb[i]):
                continue
            grow_a = la[i] / na[i] >= lb[i] / nb[i]
            cost_a, cost_b = 2 * nb[i], 2 * na[i]
            if (grow_a and cost_a <= rem) or cost_b > rem:
                na[i] += 1
                rem -= cost_a
            else:
                nb[i] += 1
                rem -= cost_b
    return na, nb


def _assemble(b, target, rng):
    frac = rng.uniform(0.3, 0.5)

    def build(res):
        return [(fn(res), orn) for fn, orn in b.parts]

    # count at a coarse resolution, then build once at the resolution that spends about
    # `frac` of the target on the res-scaled parts (counts grow roughly with res squared)
    r0 = 0.55
    built = build(r0)
    n_orn = sum(len(F) for (V, F), _ in built)
    if n_orn:
        res = float(np.clip(r0 * np.sqrt(frac * target / n_orn), r0, 1.6))
        if res > r0 + 0.03:
            built = build(res)
    n_parts = sum(len(F) for (V, F), _ in built)
    plain = [blk for blk, orn in b.blocks if not orn]
    orn_blocks = [blk for blk, orn in b.blocks if orn]
    avail = target - n_parts - 12 * len(orn_blocks)
    if plain:
        sizes = np.concatenate([blk.face_sizes() for blk in plain])
        na, nb = _pad_counts(sizes, avail)
        subs = list(zip(na, nb))
        for i, blk in enumerate(plain):
            built.append((blk.build(subs[6 * i:6 * i + 6]), False))
    for blk in orn_blocks:
        built.append((blk.build(), True))
    Vs, Fs, Ms, off = [], [], [], 0
    for (V, F), orn in built:
        Vs.append(V)
        Fs.append(F + off)
        Ms.append(np.full(len(F), orn))
        off += len(V)
    return np.concatenate(Vs), np.concatenate(Fs), np.concatenate(Ms)


def _check_names(given, allowed, what):
    if given is None:
        return tuple(allowed)
    if isinstance(given, str):
        given = [given]
    given = tuple(given)
    bad = [g for g in given if g not in allowed]
    if bad or not given:
        raise ValueError(f"unknown {what} {bad or given!r}; choose from {', '.join(allowed)}")
    return tuple(dict.fromkeys(given))


def make_shape(style, category, rng, name, n_triangles=None) -> Mesh:
    """One labelled shape. `rng` is a numpy Generator; `n_triangles` (optional) is the target
    total, otherwise drawn uniformly from TRI_RANGE."""
    _check_names([style], STYLES, "style")
    _check_names([category], CATEGORIES, "category")
    seeds = rng.integers(0, 2 ** 63, size=4)
    r_dims, r_style, r_glob, r_asm = (np.random.default_rng(int(s)) for s in seeds)
    target = int(n_triangles) if n_triangles is not None else int(r_glob.integers(TRI_RANGE[0], TRI_RANGE[1] + 1))
    scale = math.exp(r_glob.uniform(math.log(SCALE_RANGE[0]), math.log(SCALE_RANGE[1])))
    yaw = float(r_glob.uniform(0.0, 360.0))
    b = _Builder(style, r_style)
    _CATEGORY_BUILDERS[category](b, r_dims)
    V, F, mask = _assemble(b, target, r_asm)
    a = np.radians(yaw)
    c, s = np.cos(a), np.sin(a)
    Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    V = (V @ Rz.T) * scale
    V[:, 2] -= V[:, 2].min()
    V32 = V.astype(np.float32)
    # safety net: no zero-area triangle survives the float32 cast
    v = V32.astype(np.float64)
    area = 0.5 * np.linalg.norm(np.cross(v[F[:, 1]] - v[F[:, 0]], v[F[:, 2]] - v[F[:, 0]]), axis=1)
    ext = float(np.ptp(v, axis=0).max())
    ok = area > 1e-12 * ext * ext
    F, mask = F[ok], mask[ok]
    used = np.unique(F)
    remap = np.full(len(V32), -1, np.int64)
    remap[used] = np.arange(len(used))
    truth = {"style": style, "category": category, "face_mask": mask.astype(bool),
             "scale": scale, "yaw_deg": yaw}
    return Mesh(name, V32[used], remap[F].astype(np.int32), source="collection2", truth=truth)


def generate(size=120, seed=0, styles=None, categories=None) -> list[Mesh]:
    """`size` labelled shapes, round-robin over the (style, category) grid in a seeded random
    order; names c2_000, ... are assigned in a shuffled order."""
    styles = _check_names(styles, STYLES, "style")
    categories = _check_names(categories, CATEGORIES, "category")
    size = int(size)
    rng = np.random.default_rng(seed)
    grid = [(s, c) for s in styles for c in categories]
    order = rng.permutation(len(grid))
    assign = [grid[order[i % len(grid)]] for i in range(size)]
    # triangle targets stratified within each style so no style is denser on average
    targets = np.zeros(size, dtype=int)
    lo, hi = TRI_RANGE
    for st in styles:
        idx = np.array([i for i, (s, _) in enumerate(assign) if s == st], dtype=int)
        if len(idx):
            q = (rng.permutation(len(idx)) + rng.random(len(idx))) / len(idx)
            targets[idx] = np.round(lo + q * (hi - lo)).astype(int)
    position = rng.permutation(size)
    seeds = rng.integers(0, 2 ** 63, size=size)
    width = max(3, len(str(max(size - 1, 0))))
    out = [None] * size
    for i, (st, cat) in enumerate(assign):
        pos = int(position[i])
        out[pos] = make_shape(st, cat, np.random.default_rng(int(seeds[i])), f"c2_{pos:0{width}d}",
                              n_triangles=targets[i])
    return out
