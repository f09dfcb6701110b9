"""Collection 4: procedural buildings in four architectural styles, a held-out test domain.

Why: the style analysis was developed and tuned on other shapes. Buildings are a domain it has
never seen, so how well it clusters them by decorative style tells whether it generalises or
only fits what it was tuned on.

The spec, in short:
- Styles gothic, classical, pagoda, modernist; categories house, tower, hall. Each building
  carries several elements drawn from its style's own vocabulary, and no element is shared:
  gothic pointed-arch frames, buttresses, pinnacles, rose window (on a steep, plain gable);
  classical round columns (portico or engaged), low pediment, cornice band, window hoods,
  balustrade; pagoda curved roofs with upturned eaves in tiers, brackets, finial, lattice
  screens (on a plain stone platform); modernist ribbon windows, pilotis, cantilever, roof
  railing, fins (under a plain flat slab).
- Proportions (size, storeys, bays, door, wing) come from their own random stream, drawn before
  and independently of the style, so the same stream gives the same body in every style: the
  style shows only in the elements, never in the proportions.
- Every part is a separate closed, outward-wound, welded triangle solid; windows are frames,
  panels and mullions standing on the walls, not holes. 4000-40000 triangles per building
  (log-uniform target, met by the tessellation density), Z up, standing on z = 0, centred in
  plan, largest dimension log-uniform in [0.5, 500], turned by a multiple of 90 degrees.
- `truth["face_mask"]` marks the faces of the style-carrying elements; walls, floors, doors,
  platforms and plain roof planes are not style faces.

Written from that spec alone, without reading the repository's other generators (sample.py,
collection2, collection3) or the analysis code, so the collection shares no hidden assumption
with what it is meant to test.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..meshes import Mesh

STYLES = ("gothic", "classical", "pagoda", "modernist")
CATEGORIES = ("house", "tower", "hall")
SOURCE = "collection4"
TRIANGLE_RANGE = (4000, 40000)
SCALE_RANGE = (0.5, 500.0)
SIDES = ("front", "right", "back", "left")


def _check(value: str, allowed: tuple, what: str) -> str:
    if value not in allowed:
        raise ValueError(f"unknown {what} {value!r} (use one of {', '.join(allowed)})")
    return value


def _log_uniform(lo: float, hi: float, q):
    """Quantile q in [0, 1] of the log-uniform distribution on [lo, hi]."""
    return lo * (hi / lo) ** np.asarray(q, float)


# ---------------------------------------------------------------------------------------------
# Primitives. Each returns (vertices (n, 3) float64, faces (m, 3) int) of one or more closed,
# welded solids in local coordinates; the winding is made outward when a part is added.

_BOX_BITS = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float)
# Quads (a, b, c, d) of the unit box, outward; b - a and d - a run along +axes.
_BOX_QUADS = np.array([(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4),
                       (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)])


def _tris(quads: np.ndarray) -> np.ndarray:
    quads = np.asarray(quads).reshape(-1, 4)
    return np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])


_BOX_FACES = _tris(_BOX_QUADS)


def _outward(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The faces, flipped if the solid's signed volume is negative (so normals point out)."""
    p = v - v.mean(axis=0)
    a, b, c = p[f[:, 0]], p[f[:, 1]], p[f[:, 2]]
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum()
    return f if volume > 0 else f[:, ::-1].copy()


def _loft(rings, closed: bool = False, convex_caps: bool = False):
    """Skin a stack of K rings of M points each (consistently ordered). closed=True joins the
    last ring to the first (a torus: swept closed profiles); otherwise each end ring is capped
    by a fan from its centroid (from its first point if `convex_caps`: strictly convex end
    rings), or becomes a pole when all its points coincide."""
    rings = np.asarray(rings, float)
    k, m, _ = rings.shape
    idx = np.arange(k * m).reshape(k, m)
    nxt = np.roll(idx, -1, axis=1)
    rows = k if closed else k - 1
    up, up_nxt = np.roll(idx, -1, axis=0), np.roll(nxt, -1, axis=0)
    quads = np.stack([idx[:rows], nxt[:rows], up_nxt[:rows], up[:rows]], -1)
    verts, faces = [rings.reshape(-1, 3)], [_tris(quads)]
    remap = list(range(k * m))
    count = k * m
    if not closed:
        for ring_i, top in ((0, False), (k - 1, True)):
            ring = rings[ring_i]
            if np.all(ring == ring[0]):
                for j in idx[ring_i]:
                    remap[j] = idx[ring_i, 0]
                continue
            if convex_caps:
                centre, i, j = np.full(m - 2, idx[ring_i, 0]), idx[ring_i, 1:-1], idx[ring_i, 2:]
            else:
                verts.append(ring.mean(axis=0)[None])
                remap.append(count)
                centre = np.full(m, count)
                count += 1
                i, j = idx[ring_i], nxt[ring_i]
            faces.append(np.stack([centre, i, j] if top else [centre, j, i], 1))
    v = np.concatenate(verts)
    f = np.asarray(remap)[np.concatenate(faces)]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
    used, f = np.unique(f, return_inverse=True)
    return v[used], f.reshape(-1, 3)


def _lathe(profile, n: int, phase: float = 0.0):
    """Solid of revolution about local +z: profile (r, z) from bottom to top, n sides (n = 4
    with phase pi/4 is a square pyramid or prism). r = 0 at an end closes it on a pole."""
    p = np.asarray(profile, float)
    ang = phase + 2 * np.pi * np.arange(n) / n
    r = p[:, :1]
    rings = np.stack([r * np.cos(ang), r * np.sin(ang),
                      np.broadcast_to(p[:, 1:], (len(p), n))], -1)
    return _loft(rings)


def _prism(outline, w0: float, w1: float):
    """A convex 2D outline (u, v) extruded along w from w0 to w1."""
    o = np.asarray(outline, float)
    ring = lambda w: np.column_stack([o, np.full(len(o), w)])
    return _loft([ring(w0), ring(w1)], convex_caps=True)


def _band(inner, outer, w0: float, w1: float, closed: bool = False):
    """A frame or moulding: the strip between two matching 2D polylines, extruded from w0 to
    w1 (an arch frame; closed=True for a ring such as the rose window's)."""
    inner, outer = np.asarray(inner, float), np.asarray(outer, float)
    col = lambda p, w: np.column_stack([p, np.full(len(p), w)])
    rings = np.stack([col(inner, w0), col(outer, w0), col(outer, w1), col(inner, w1)], 1)
    return _loft(rings, closed, convex_caps=True)


def _grid_box(lo, hi, n):
    """An axis-aligned box whose faces are divided into an n = (nx, ny, nz) grid, welded:
    plain walls carry the part of the triangle budget the details do not use."""
    n = np.asarray(n, int)
    pts, quads, base = [], [], 0
    for a, b, _, d in _BOX_QUADS:
        start = _BOX_BITS[a].astype(int) * n
        e1 = int(np.argmax(_BOX_BITS[b] != _BOX_BITS[a]))
        e2 = int(np.argmax(_BOX_BITS[d] != _BOX_BITS[a]))
        i, j = np.meshgrid(np.arange(n[e1] + 1), np.arange(n[e2] + 1), indexing="ij")
        p = np.repeat(start[None], i.size, 0)
        p[:, e1] += i.ravel()
        p[:, e2] += j.ravel()
        ids = base + i * (n[e2] + 1) + j
        quads.append(np.stack([ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:], ids[:-1, 1:]], -1))
        pts.append(p)
        base += len(p)
    p = np.concatenate(pts)
    key = (p[:, 0] * (n[1] + 1) + p[:, 1]) * (n[2] + 1) + p[:, 2]
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    lattice = p[first]
    axes = [np.linspace(lo[k], hi[k], n[k] + 1) for k in range(3)]
    v = np.column_stack([axes[k][lattice[:, k]] for k in range(3)])
    q = np.concatenate([x.reshape(-1, 4) for x in quads])
    return v, _tris(inverse.ravel()[q])


def _grid_divisions(size: np.ndarray, step: float) -> np.ndarray:
    """Divisions (k, 3) of boxes of the given sizes at a grid step. Box k's step is
    stretched by up to 30% (a fixed low-discrepancy sequence), so that many equal boxes (a
    row of mullions) do not all split at once and the count can be aimed finely."""
    stretch = 1 + 0.3 * ((np.arange(len(size)) * 0.6180339887) % 1.0)
    return np.maximum(1, np.ceil(size / (step * stretch[:, None]) - 1e-9)).astype(int)


def _grid_count(size: np.ndarray, step: float) -> int:
    """Triangles of `_grid_box`es of the given sizes (k, 3) at a grid step."""
    n = _grid_divisions(size, step)
    return int((4 * (n[:, 0] * n[:, 1] + n[:, 1] * n[:, 2] + n[:, 2] * n[:, 0])).sum())


def _pointed_arch(span: float, rho: float, width: float, n: int, jamb: float):
    """Inner and outer outline of a pointed-arch frame of `width` (u across, v up from the
    springing line): each side is a circular arc of radius rho * span centred on the springing
    line at the other side (rho = 1: equilateral arch), the two meeting in a cusp on u = 0;
    jambs run down to v = -jamb."""
    s, r = span / 2, rho * span
    c = r - s                                   # the left arc's centre is (c, 0)
    t = np.linspace(0.0, 1.0, n + 1)

    def side(radius, half):
        theta = t * math.acos(c / radius)
        arc = np.column_stack([c - radius * np.cos(theta), radius * np.sin(theta)])
        left = np.vstack([[-half, -jamb], arc])
        right = left[:-1][::-1] * [-1, 1]
        return np.vstack([left, right])

    return side(r, s), side(r + width, s + width)


# ---------------------------------------------------------------------------------------------
# Collecting the parts of one building


class _Parts:
    """The closed solids of one building, each flagged as style-carrying or not. Axis-aligned
    boxes (walls, slabs, sills, mullions...) are kept as (lo, hi): at the end their faces are
    divided on a common grid to meet the triangle budget, so flat surfaces share it evenly."""

    def __init__(self):
        self.lo, self.hi, self.box_style = [], [], []
        self.solids = []                 # (v, f, style); v may hold several disjoint parts

    def box(self, lo, hi, style: bool, place=None):
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        corners = _BOX_BITS * np.abs(hi - lo) + np.minimum(lo, hi)
        if place is not None:
            corners = place(corners)
        c_lo, c_hi = corners.min(axis=0), corners.max(axis=0)
        if np.all((np.abs(corners - c_lo) < 1e-12) | (np.abs(corners - c_hi) < 1e-12)):
            self.lo.append(c_lo)
            self.hi.append(c_hi)
            self.box_style.append(style)
        else:                            # turned out of the axes (rose spokes)
            self.solid((corners, _BOX_FACES), style)

    def wall(self, lo, hi):
        self.box(lo, hi, False)

    def solid(self, vf, style: bool, place=None, offsets=None):
        """Add a solid (mapped by `place`), or one copy per offset (instances)."""
        v, f = vf
        if place is not None:
            v = place(v)
        f = _outward(v, f)
        if offsets is not None:
            offsets = np.asarray(offsets, float).reshape(-1, 3)
            f = (f[None] + len(v) * np.arange(len(offsets))[:, None, None]).reshape(-1, 3)
            v = (v[None] + offsets[:, None]).reshape(-1, 3)
        if len(f):
            self.solids.append((v, f, style))

    def _sizes(self) -> np.ndarray:
        return (np.asarray(self.hi) - np.asarray(self.lo)).reshape(-1, 3)

    def count(self, step: float = math.inf) -> int:
        """Triangles with the boxes divided at grid `step`."""
        return _grid_count(self._sizes(), step) + sum(len(f) for _, f, _ in self.solids)

    def box_step(self, target: int, allowed=TRIANGLE_RANGE) -> float:
        """The grid step that brings the total closest to `target` triangles, keeping it
        within `allowed` when the grid's jumps allow either side."""
        if self.count() >= target:
            return math.inf
        lo, hi = 1e-4 * self._sizes().max(), self._sizes().max()
        for _ in range(50):
            mid = math.sqrt(lo * hi)
            lo, hi = (mid, hi) if self.count(mid) > target else (lo, mid)
        inside = lambda h: allowed[0] <= self.count(h) <= allowed[1]
        return min((lo, hi), key=lambda h: (not inside(h), abs(self.count(h) - target)))

    def assemble(self, step: float):
        """(vertices, faces, style mask) of all parts, boxes divided at grid `step`."""
        pieces = []
        lo, hi, style = np.asarray(self.lo), np.asarray(self.hi), np.asarray(self.box_style)
        n = _grid_divisions((hi - lo).reshape(-1, 3), step)
        plain = np.all(n == 1, axis=1)
        for k in np.flatnonzero(~plain):
            pieces.append((*_grid_box(lo[k], hi[k], n[k]), bool(style[k])))
        if plain.any():
            corners = _BOX_BITS[None] * (hi - lo)[plain, None] + lo[plain, None]
            faces = _BOX_FACES[None] + 8 * np.arange(len(corners))[:, None, None]
            pieces.append((corners.reshape(-1, 3), faces.reshape(-1, 3),
                           np.repeat(style[plain], 12)))
        pieces += self.solids
        vs, fs, ms, base = [], [], [], 0
        for v, f, st in pieces:
            vs.append(v)
            fs.append(f + base)
            ms.append(np.broadcast_to(st, len(f)))
            base += len(v)
        return np.concatenate(vs), np.concatenate(fs), np.concatenate(ms).astype(bool)


# ---------------------------------------------------------------------------------------------
# Proportions: the style-free body of a building


def proportions(category: str, rng: np.random.Generator) -> dict:
    """The body of a building (metres): footprint, storeys, bays, door, wing. Drawn from its own
    stream before any style draw, so a stream gives the same body in every style."""
    _check(category, CATEGORIES, "category")
    u = rng.uniform
    if category == "house":
        storeys = int(rng.choice([1, 2, 2, 2, 3]))
        storey_h = u(2.8, 3.4)
        long_side, ratio = u(8.0, 13.0), u(1.0, 1.6)
        width, depth = ((long_side, long_side / ratio) if rng.random() < 0.5
                        else (long_side / ratio, long_side))
        bay_x = bay_y = u(2.6, 3.4)
        wing_p, wing_w, wing_d = 0.45, u(0.35, 0.6), u(0.5, 0.85)
        wing_storeys, wing_h = max(1, storeys - 1), storey_h
    elif category == "tower":
        width = u(5.0, 8.0)
        depth = width * u(1.0, 1.25)
        wall_h = depth * u(2.5, 5.0)
        storeys = int(np.clip(round(wall_h / u(3.5, 5.5)), 3, 7))
        storey_h = wall_h / storeys
        bay_x, bay_y = u(3.5, 5.0), u(4.0, 6.0)
        wing_p, wing_w, wing_d = 0.3, u(0.35, 0.5), u(0.5, 0.8)
        wing_storeys, wing_h = 1, min(storey_h, 4.0)
    else:
        width = u(8.0, 13.0)
        depth = width * u(2.5, 4.0)
        storeys, storey_h = 1, u(5.0, 8.0)
        bay_x, bay_y = width / 3 if rng.random() < 0.6 else width, u(3.0, 4.5)
        wing_p, wing_w, wing_d = 0.35, u(0.3, 0.45), u(0.2, 0.35)
        wing_storeys, wing_h = 1, storey_h * u(0.55, 0.7)
    bays_x = max(1, int(round(width / bay_x)))
    bays_y = max(1, int(round(depth / bay_y)))
    door_bay = bays_x // 2 if rng.random() < 0.6 else int(rng.integers(bays_x))
    has_wing = bool(rng.random() < wing_p)
    side, offset = (1 if rng.random() < 0.5 else -1), u(-1.0, 1.0)
    wing = None
    if has_wing:
        ww, wd = width * wing_w, depth * wing_d
        wing = dict(side=side, width=ww, depth=wd, offset=offset, storeys=wing_storeys,
                    storey_h=wing_h, bays_x=max(1, int(round(ww / bay_y))),
                    bays_y=max(1, int(round(wd / bay_y))))
    # towers light every other storey, counting down from the top one
    window_storeys = [k for k in range(storeys)
                      if category != "tower" or (storeys - 1 - k) % 2 == 0]
    return dict(category=category, width=width, depth=depth, storeys=storeys,
                storey_h=storey_h, bays_x=bays_x, bays_y=bays_y, door_bay=door_bay,
                window_storeys=window_storeys,
                window_w=u(0.35, 0.5), window_h=u(0.45, 0.6),
                door_w=u(1.1, 1.6), door_h=u(2.1, 2.6) * (1.4 if category == "hall" else 1.0),
                wing=wing)


@dataclass
class _Block:
    """An axis-aligned wall block. `hidden[side]` lists (u0, u1, z_top) spans of a facade that
    another block covers (no windows or elements there)."""
    x0: float
    x1: float
    y0: float
    y1: float
    z0: float
    storeys: int
    storey_h: float
    bays_x: int
    bays_y: int
    door_bay: int | None = None
    hidden: dict = field(default_factory=dict)
    window_storeys: list | None = None      # storeys with windows (None: all)

    @property
    def top(self) -> float:
        return self.z0 + self.storeys * self.storey_h

    def facades(self):
        return [_Facade(self, s) for s in SIDES if (-math.inf, math.inf, math.inf)
                not in self.hidden.get(s, [])]


class _Facade:
    """One wall face of a block, with local coordinates u (along the face, left to right seen
    from outside), z (up) and n (outward)."""

    def __init__(self, block: _Block, side: str):
        x0, x1, y0, y1 = block.x0, block.x1, block.y0, block.y1
        origin, u_dir, n_dir, self.length, self.bays = {
            "front": ((x0, y0), (1, 0), (0, -1), x1 - x0, block.bays_x),
            "right": ((x1, y0), (0, 1), (1, 0), y1 - y0, block.bays_y),
            "back": ((x1, y1), (-1, 0), (0, 1), x1 - x0, block.bays_x),
            "left": ((x0, y1), (0, -1), (-1, 0), y1 - y0, block.bays_y)}[side]
        self.block, self.side = block, side
        self.origin = np.array([*origin, 0.0])
        self.axes = np.array([[*u_dir, 0.0], [0.0, 0.0, 1.0], [*n_dir, 0.0]])
        self.hidden = block.hidden.get(side, [])

    def place(self, local):
        """Local (u, z, n) to world."""
        return self.origin + np.asarray(local, float) @ self.axes

    def place_nzu(self, local):
        """Local (n, z, u) to world (outlines drawn in the side view, extruded along u)."""
        return self.origin + np.asarray(local, float) @ self.axes[[2, 1, 0]]

    def point(self, u, z, n=0.0):
        return self.place([[u, z, n]])[0]

    def covered(self, u0, u1, z) -> bool:
        return any(u1 > h0 and u0 < h1 and z < zt for h0, h1, zt in self.hidden)

    def door(self, plan):
        """(u centre, width, height) of the entrance, on the ground storey of the front."""
        b = self.block
        if self.side != "front" or b.door_bay is None:
            return None
        bay = self.length / self.bays
        return ((b.door_bay + 0.5) * bay, min(plan["door_w"], 0.8 * bay),
                min(plan["door_h"], 0.8 * b.storey_h))

    def windows(self, plan, storeys=None):
        """(u centre, sill z, width, height) of each window opening; the door's bay and the
        wall covered by another block are left out."""
        b, bay = self.block, self.length / self.bays
        ww, wh = plan["window_w"] * bay, plan["window_h"] * b.storey_h
        out = []
        for k in range(b.storeys) if storeys is None else storeys:
            if b.window_storeys is not None and k not in b.window_storeys:
                continue
            sill = b.z0 + k * b.storey_h + 0.45 * (b.storey_h - wh)
            for i in range(self.bays):
                uc = (i + 0.5) * bay
                if k == 0 and self.side == "front" and b.door_bay == i:
                    continue
                if not self.covered(uc - ww / 2, uc + ww / 2, sill):
                    out.append((uc, sill, ww, wh))
        return out


def _blocks(plan: dict, z0: float):
    """The main block and the wing (or None) standing at z0."""
    w, d = plan["width"], plan["depth"]
    main = _Block(-w / 2, w / 2, -d / 2, d / 2, z0, plan["storeys"], plan["storey_h"],
                  plan["bays_x"], plan["bays_y"], plan["door_bay"],
                  window_storeys=plan["window_storeys"])
    spec = plan["wing"]
    if spec is None:
        return main, None
    yc = spec["offset"] * (d - spec["depth"]) / 2
    y0, y1 = yc - spec["depth"] / 2, yc + spec["depth"] / 2
    if spec["side"] > 0:
        x0, x1, contact, own = w / 2, w / 2 + spec["width"], "right", "left"
        span = (y0 + d / 2, y1 + d / 2)
    else:
        x0, x1, contact, own = -w / 2 - spec["width"], -w / 2, "left", "right"
        span = (d / 2 - y1, d / 2 - y0)
    wing = _Block(x0, x1, y0, y1, z0, spec["storeys"], spec["storey_h"], spec["bays_x"],
                  spec["bays_y"], None, {own: [(-math.inf, math.inf, math.inf)]})
    main.hidden[contact] = [(*span, wing.top)]
    return main, wing


# ---------------------------------------------------------------------------------------------
# The builder: what every style shares


class _Builder:
    """One building under construction: its proportions, its style stream, the tessellation
    density `res` in [0, 1] and the parts collected so far."""

    def __init__(self, plan: dict, rng: np.random.Generator, res: float):
        self.plan, self.rng, self.res = plan, rng, res
        self.parts = _Parts()
        self.body_corners = None
        wing = plan["wing"]
        size = max(plan["width"] + (wing["width"] if wing else 0.0), plan["depth"],
                   plan["storeys"] * plan["storey_h"])
        # Largest gap between a curve and its chords: from a 400th of the building (half a
        # pixel in a 200 px drawing) at the coarsest density, 30 times finer at the finest.
        self.sagitta = size / (400.0 * 30.0 ** res)

    def seg(self, lo: int, hi: int) -> int:
        """A tessellation count between lo (coarsest) and hi (finest) at this density, for
        curves as large as the building (eaves)."""
        return int(round(lo + (hi - lo) * self.res))

    def arc(self, radius: float, angle: float, lo: int = 2, hi: int = 48) -> int:
        """Segments of an arc, so that no chord strays more than `self.sagitta` from it."""
        step = math.sqrt(8 * self.sagitta / radius) if radius > 2 * self.sagitta else np.pi
        return int(np.clip(math.ceil(abs(angle) / step), lo, hi))

    def sides(self, radius: float, lo: int = 8, hi: int = 64) -> int:
        """Sides of a round part of this radius."""
        return self.arc(radius, 2 * np.pi, lo, hi)

    def walls(self, x0, x1, y0, y1, z0, z1, main=False):
        self.parts.wall((x0, y0, z0), (x1, y1, z1))
        if main and self.body_corners is None:
            self.body_corners = np.array([[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]])

    def block_walls(self, block: _Block, main=False):
        self.walls(block.x0, block.x1, block.y0, block.y1, block.z0, block.top, main)

    def fbox(self, fac: _Facade, u0, u1, z0, z1, n0, n1, style):
        self.parts.box((u0, z0, n0), (u1, z1, n1), style, fac.place)

    def panel(self, fac, uc, z0, w, h, n1=0.06, style=False):
        """A flat window or door panel standing a little out of the wall."""
        self.fbox(fac, uc - w / 2, uc + w / 2, z0, z0 + h, -0.05, n1, style)

    def door(self, fac):
        door = fac.door(self.plan)
        if door is not None:
            uc, dw, dh = door
            self.panel(fac, uc, fac.block.z0, dw, dh, 0.1)
        return door

    def flat_slab(self, block, overhang, thickness, style=False):
        self.parts.box((block.x0 - overhang, block.y0 - overhang, block.top),
                       (block.x1 + overhang, block.y1 + overhang, block.top + thickness), style)

    def gable(self, block, pitch, overhang, style=False):
        """A gable roof (triangular prism) along the block's longer side; returns its apex z."""
        along_x = block.x1 - block.x0 >= block.y1 - block.y0
        half = (block.y1 - block.y0 if along_x else block.x1 - block.x0) / 2
        centre = (block.y0 + block.y1 if along_x else block.x0 + block.x1) / 2
        t = math.tan(pitch)
        top = block.top
        outline = [(centre - half - overhang, top - overhang * t),
                   (centre + half + overhang, top - overhang * t), (centre, top + half * t)]
        if along_x:
            vf, axes = _prism(outline, block.x0, block.x1), [[0, 1, 0], [0, 0, 1], [1, 0, 0]]
        else:
            vf, axes = _prism(outline, block.y0, block.y1), [[1, 0, 0], [0, 0, 1], [0, 1, 0]]
        self.parts.solid(vf, style, lambda v: v @ np.array(axes, float))
        return top + half * t

    def tube(self, p0, p1, radius, n, style=True):
        """A round bar from p0 to p1."""
        p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
        axis = p1 - p0
        length = float(np.linalg.norm(axis))
        w = axis / length
        a = np.cross(w, [0.0, 0.0, 1.0] if abs(w[2]) < 0.9 else [1.0, 0.0, 0.0])
        a /= np.linalg.norm(a)
        frame = np.array([a, np.cross(w, a), w])
        vf = _lathe([(0, 0), (radius, 0), (radius, length), (0, length)], n)
        self.parts.solid(vf, style, lambda v: p0 + v @ frame)


def _pick(rng, probabilities: dict, at_least: int) -> set:
    """Optional elements drawn independently, topped up at random to `at_least` of them."""
    on = {k for k, p in probabilities.items() if rng.random() < p}
    off = [k for k, p in probabilities.items() if k not in on and p > 0]
    while len(on) < at_least and off:
        on.add(off.pop(int(rng.integers(len(off)))))
    return on


# ---------------------------------------------------------------------------------------------
# Gothic


def _gothic(b: _Builder):
    rng, plan = b.rng, b.plan
    hall = plan["category"] == "hall"
    rho = rng.uniform(1.0, 1.3)                  # equilateral to lancet arches
    frame = rng.uniform(0.10, 0.16)
    pitch = math.radians(rng.uniform(50, 60))
    overhang = rng.uniform(0.25, 0.5)
    mullion = rng.random() < 0.5
    pinnacle_sides = 4 if rng.random() < 0.5 else 8
    pinnacle_h = rng.uniform(0.25, 0.4) * min(plan["width"], plan["depth"])
    stages = int(rng.integers(2, 4))
    spokes = int(rng.choice([8, 12, 16]))
    opts = _pick(rng, {"buttresses": 0.7, "pinnacles": 0.6, "rose": 0.85 if hall else 0.0},
                 2 if hall else 1)
    main, wing = _blocks(plan, 0.0)
    for block in (main, wing):
        if block is None:
            continue
        b.block_walls(block, main=block is main)
        b.gable(block, pitch, overhang)
        buttress_tops = []
        for fac in block.facades():
            for uc, sill, ww, wh in fac.windows(plan):
                _arch_window(b, fac, uc, sill, ww, wh, rho, frame, mullion)
            door = b.door(fac)
            if door is not None:
                uc, dw, dh = door
                _arch(b, fac, uc, block.z0, dw + 0.1, dh, rho, frame, tympanum=True)
            if "buttresses" in opts:
                buttress_tops += _buttresses(b, fac, stages, "pinnacles" in opts)
        if "pinnacles" in opts:
            bw = min(0.6, 0.18 * block.storey_h)
            if not buttress_tops:   # on the corners of the wall head instead
                buttress_tops = [(x, y, block.top, bw) for x in (block.x0, block.x1)
                                 for y in (block.y0, block.y1)]
            for x, y, z, width in buttress_tops:
                _pinnacle(b, x, y, z, 0.8 * width, pinnacle_h, pinnacle_sides)
    if "rose" in opts:
        _rose(b, main, pitch, spokes)


def _arch(b, fac, uc, z_base, span, jamb, rho, frame, tympanum=False):
    """A pointed-arch frame over an opening (springing at z_base + jamb); with `tympanum`
    the pointed field above the springing is filled (over a door)."""
    r = (rho + frame) * span
    n_arc = b.arc(r, math.acos((rho - 0.5) * span / r), lo=2)
    inner, outer = _pointed_arch(span, rho, frame * span, n_arc, jamb)
    place = lambda v: fac.place(v + [uc, z_base + jamb, 0.0])
    b.parts.solid(_band(inner, outer, -0.05, 0.14), True, place)
    if tympanum:
        arc = inner[1:-1]                        # the two arcs, from springing to springing
        b.parts.solid(_prism(arc, -0.05, 0.06), True, place)


def _arch_window(b, fac, uc, sill, ww, wh, rho, frame, mullion):
    """A lancet: pointed frame, sill and, sometimes, a central mullion."""
    r = rho * ww
    rise = math.sqrt(r * r - (r - ww / 2) ** 2)
    jamb = max(0.3 * wh, wh - rise)
    _arch(b, fac, uc, sill, ww, jamb, rho, frame)
    f = frame * ww
    b.fbox(fac, uc - ww / 2 - f - 0.06, uc + ww / 2 + f + 0.06, sill - 0.1, sill, -0.05, 0.2, True)
    if mullion:
        b.fbox(fac, uc - 0.04 * ww, uc + 0.04 * ww, sill, sill + jamb + 0.5 * rise,
               -0.05, 0.1, True)


def _buttresses(b, fac, stages, flat_top):
    """Stepped piers against the wall at the bay divisions and the corners; returns the tops
    (x, y, z, width) where pinnacles may stand."""
    block = fac.block
    bay = fac.length / fac.bays
    bw = min(0.6, 0.18 * bay, 0.18 * block.storey_h * block.storeys)
    depth = bw * (1.2 + 0.6 * (block.storey_h * block.storeys > 8))
    top = block.top - (0.0 if flat_top else 0.08 * block.storey_h)
    heights = block.z0 + (top - block.z0) * np.r_[0.0, np.cumsum(np.linspace(1.4, 0.6, stages))
                                                  / np.linspace(1.4, 0.6, stages).sum()]
    tops = []
    for j in range(fac.bays + 1):
        u = min(max(j * bay, bw / 2), fac.length - bw / 2)
        if fac.covered(u - bw / 2, u + bw / 2, block.z0):
            continue
        for k in range(stages):
            z0, z1 = heights[k], heights[k + 1]
            dk = depth * (1 - 0.3 * k)
            slope = 0.0 if (flat_top and k == stages - 1) else min(0.5 * (z1 - z0), 0.8 * dk)
            outline = [(-0.05, z0), (dk, z0), (dk, z1 - slope), (-0.05, z1)]
            b.parts.solid(_prism(outline, u - bw / 2, u + bw / 2), True, fac.place_nzu)
        if flat_top:
            x, y, _ = fac.point(u, top, depth * (1 - 0.3 * (stages - 1)) / 2)
            tops.append((x, y, top, bw))
    return tops


def _pinnacle(b, x, y, z, width, height, sides):
    """A small square shaft crowned by a tall thin pyramid."""
    half = width / 2
    shaft = 0.2 * height
    b.parts.box((x - half, y - half, z - 0.05), (x + half, y + half, z + shaft), True)
    r = half * (math.sqrt(2) if sides == 4 else 1.0)
    vf = _lathe([(0, 0), (r, 0), (0, 0.8 * height)], sides, math.pi / 4 if sides == 4 else 0.0)
    b.parts.solid(vf, True, offsets=[(x, y, z + shaft)])


def _rose(b, block, pitch, spokes):
    """A rose window on the front gable: outer and inner rings, hub and radial spokes."""
    fac = _Facade(block, "front")
    w = block.x1 - block.x0
    h = w / 2 * math.tan(pitch)
    inradius = w * h / (w + 2 * math.hypot(w / 2, h))
    radius, uc, zc = 0.8 * inradius, w / 2, block.top + inradius
    n = b.sides(radius, lo=16, hi=128)
    ang = 2 * np.pi * np.arange(n) / n
    circle = np.column_stack([np.cos(ang), np.sin(ang)])
    place = lambda v: fac.place(v + [uc, zc, 0.0])
    for r_out, width in ((radius, 0.12 * radius), (0.55 * radius, 0.07 * radius)):
        b.parts.solid(_band(circle * (r_out - width), circle * r_out, -0.02, 0.18, True),
                      True, place)
    b.parts.solid(_prism(circle * 0.18 * radius, -0.02, 0.2), True, place)
    b.parts.solid(_prism(circle * radius, -0.03, 0.03), True, place)
    t = 0.025 * radius
    for k in range(spokes):
        a = 2 * np.pi * (k + 0.5) / spokes
        rot = np.array([[math.cos(a), math.sin(a), 0], [-math.sin(a), math.cos(a), 0], [0, 0, 1]])
        b.parts.box((0.17 * radius, -t, -0.02), (0.9 * radius, t, 0.12), True,
                    lambda v, rot=rot: place(v @ rot))


# ---------------------------------------------------------------------------------------------
# Classical


def _classical(b: _Builder):
    rng, plan = b.rng, b.plan
    cat = plan["category"]
    portico = rng.random() < (0.4 if cat == "tower" else 0.65)
    pitch = math.radians(rng.uniform(15, 25))
    hood_triangle = rng.random() < 0.5
    hood_pitch = math.radians(rng.uniform(18, 24))
    col_ratio = rng.uniform(8, 10)                    # column height / diameter
    n_cols = int(rng.choice([4, 6, 8]))
    cornice_h = rng.uniform(0.45, 0.7) * min(1.5, plan["storey_h"] / 3)
    opts = _pick(rng, {"pediment": 0.75, "cornice": 0.8, "hoods": 0.7, "balustrade": 0.6}, 2)
    flat = "balustrade" in opts
    main, wing = _blocks(plan, 0.0)
    for block in (main, wing):
        if block is None:
            continue
        b.block_walls(block, main=block is main)
        if flat:
            b.flat_slab(block, 0.15, 0.2)
        else:
            b.gable(block, pitch, 0.3)
        if "cornice" in opts:
            _cornice(b, block, cornice_h)
        for fac in block.facades():
            for uc, sill, ww, wh in fac.windows(plan):
                b.panel(fac, uc, sill, ww, wh)
                b.fbox(fac, uc - ww / 2 - 0.08, uc + ww / 2 + 0.08, sill - 0.1, sill,
                       -0.05, 0.15, False)
                if "hoods" in opts:
                    _hood(b, fac, uc, sill + wh, ww, hood_triangle, hood_pitch)
            door = b.door(fac)
            if door is not None and "hoods" in opts and not portico:
                _hood(b, fac, door[0], block.z0 + door[2], door[1], hood_triangle, hood_pitch)
    front = _Facade(main, "front")
    if portico:
        _portico(b, main, plan, n_cols, col_ratio, pitch, opts)
    else:
        _engaged_columns(b, main, col_ratio, cornice_h if "cornice" in opts else 0.0)
    along_x = main.x1 - main.x0 >= main.y1 - main.y0
    skip = None
    if "pediment" in opts and not portico:
        if not flat and not along_x:           # the front is the gable end: a temple front
            w = main.x1 - main.x0
            outline = [(0, main.top), (w, main.top), (w / 2, main.top + w / 2 * math.tan(pitch))]
            b.parts.solid(_prism(outline, -0.1, 0.35), True, front.place)
            b.fbox(front, -0.1, w + 0.1, main.top - 0.25, main.top, -0.1, 0.4, True)
        else:                                  # a central frontispiece on the wall head
            bay = front.length / front.bays
            pw = min(0.6 * front.length, 3 * bay)
            u0 = front.length / 2 - pw / 2
            outline = [(u0, main.top), (u0 + pw, main.top),
                       (u0 + pw / 2, main.top + pw / 2 * math.tan(pitch))]
            b.parts.solid(_prism(outline, -0.3, 0.4), True, front.place)
            skip = (u0 - 0.2, u0 + pw + 0.2)
    if flat and not (portico and "pediment" not in opts):    # else it is on the portico
        z = main.top + 0.2
        spans = [(0.2 * front.length, 0.8 * front.length)]      # a parapet over the centre
        if skip is not None:
            spans = [(0.1 * front.length, skip[0]), (skip[1], 0.9 * front.length)]
        for u0, u1 in spans:
            if u1 - u0 > 1.0:
                _balustrade(b, front.point(u0, z, -0.3), front.point(u1, z, -0.3), 0.9)


def _column(b, diameter, height):
    """A column standing at the origin: square plinth, torus, round tapering shaft with a
    slight entasis, echinus and square abacus (several closed parts)."""
    d, r = diameter, diameter / 2
    n = b.sides(0.6 * d)
    parts = []

    def box(lo, hi):
        return _BOX_BITS * (np.array(hi) - lo) + lo, _BOX_FACES

    parts.append(box((-0.65 * d, -0.65 * d, 0), (0.65 * d, 0.65 * d, 0.25 * d)))
    t = np.linspace(0, 1, b.arc(0.1 * d, np.pi, lo=1, hi=12) + 1)
    torus = np.column_stack([r + 0.12 * d * np.sin(np.pi * t), 0.25 * d + 0.2 * d * t])
    parts.append(_lathe(np.vstack([[0, 0.2 * d], torus, [0, 0.45 * d]]), n))
    shaft_h = height - 0.9 * d
    z = np.linspace(0, 1, b.seg(2, 10))
    shaft = np.column_stack([r * (1 - 0.16 * z ** 1.5), 0.45 * d + shaft_h * z])
    parts.append(_lathe(np.vstack([[0, 0.45 * d], shaft, [0, 0.45 * d + shaft_h]]), n))
    z0 = 0.45 * d + shaft_h
    t = np.linspace(0, 1, b.arc(0.3 * d, np.pi / 2, lo=1, hi=12) + 1)
    echinus = np.column_stack([0.84 * r + 0.4 * r * np.sin(0.5 * np.pi * t), z0 - 0.02 * d
                               + 0.27 * d * t])
    parts.append(_lathe(np.vstack([[0, z0 - 0.02 * d], echinus, [0, z0 + 0.25 * d]]), n))
    parts.append(box((-0.65 * d, -0.65 * d, z0 + 0.25 * d), (0.65 * d, 0.65 * d, height)))
    vs, fs, base = [], [], 0
    for v, f in parts:
        vs.append(v)
        fs.append(_outward(v, f) + base)
        base += len(v)
    return np.concatenate(vs), np.concatenate(fs)


def _portico(b, block, plan, n_cols, col_ratio, pitch, opts):
    """Free-standing columns before the front on a stepped base, under an entablature and a
    pediment (or a balustrade)."""
    fac = _Facade(block, "front")
    tower = plan["category"] == "tower"
    height = block.storey_h if tower else block.top
    pw = 0.9 * fac.length
    base_h = 0.3
    d = min(height / (col_ratio + 1.4), pw / (2.6 * (n_cols - 1) + 1.3))
    entablature = 1.1 * d
    depth = max(2.6 * d + 0.6, 1.6)
    uc = fac.length / 2
    u0, u1 = uc - pw / 2, uc + pw / 2
    b.fbox(fac, u0 - 0.3, u1 + 0.3, 0.0, base_h, 0.0, depth + 0.3, False)
    col_h = height - base_h - entablature
    us = np.linspace(u0 + 0.65 * d, u1 - 0.65 * d, n_cols)
    centres = fac.place(np.column_stack([us, np.full(n_cols, base_h), np.full(n_cols, depth
                                                                                 - 0.8 * d)]))
    b.parts.solid(_column(b, d, col_h), True, offsets=centres)
    z = height - entablature
    b.fbox(fac, u0, u1, z, z + 0.65 * entablature, -0.05, depth - 0.1 * d, True)
    b.fbox(fac, u0 - 0.15 * d, u1 + 0.15 * d, z + 0.65 * entablature, height, -0.05,
           depth + 0.05, True)
    if "pediment" in opts:
        outline = [(u0 - 0.15 * d, height), (u1 + 0.15 * d, height),
                   (uc, height + (pw / 2 + 0.15 * d) * math.tan(pitch))]
        b.parts.solid(_prism(outline, -0.1, depth + 0.05), True, fac.place)
    elif "balustrade" in opts:
        _balustrade(b, fac.point(u0 + 0.2, height, depth - 0.25),
                    fac.point(u1 - 0.2, height, depth - 0.25), 0.9)


def _engaged_columns(b, block, col_ratio, cornice_h):
    """Round columns half sunk into the walls at the bay divisions: on the front (per storey
    on towers), and on every other division of a hall's long sides."""
    plan = b.plan
    tower = plan["category"] == "tower"
    sides = ("front", "right", "left") if plan["category"] == "hall" else ("front",)
    orders = ([(block.z0 + k * block.storey_h, block.storey_h) for k in range(block.storeys)]
              if tower else [(block.z0, block.top - block.z0 - cornice_h)])
    for side in sides:
        fac = _Facade(block, side)
        if (-math.inf, math.inf, math.inf) in fac.hidden:
            continue
        for z0, height in orders:
            d = height / (col_ratio + 1.4)
            step = 1 if side == "front" else 2
            us = [min(max(j * fac.length / fac.bays, 0.7 * d), fac.length - 0.7 * d)
                  for j in range(0, fac.bays + 1, step)]
            us = [u for u in us if not fac.covered(u - d, u + d, z0)]
            if us:
                centres = fac.place([(u, z0, 0.3 * d) for u in us])
                b.parts.solid(_column(b, d, height), True, offsets=centres)


def _cornice(b, block, height):
    """A continuous moulding under the roof line: an ovolo profile swept round the block."""
    proj = 0.7 * height
    theta = np.linspace(0, np.pi / 2, b.arc(proj, np.pi / 2, lo=2, hi=16) + 1)
    ovolo = np.column_stack([0.15 * height + (proj - 0.15 * height) * (1 - np.cos(theta)),
                             -0.75 * height + 0.55 * height * np.sin(theta)])
    profile = np.vstack([[(-0.1, -height), (0.1 * height, -height), (0.1 * height, -0.8 * height)],
                         ovolo, [(proj, 0.0), (-0.1, 0.0)]])
    rings = []
    for x, y, sx, sy in ((block.x0, block.y0, -1, -1), (block.x1, block.y0, 1, -1),
                         (block.x1, block.y1, 1, 1), (block.x0, block.y1, -1, 1)):
        rings.append(np.column_stack([x + sx * profile[:, 0], y + sy * profile[:, 0],
                                      block.top + profile[:, 1]]))
    b.parts.solid(_loft(rings, closed=True), True)


def _hood(b, fac, uc, z, width, triangle, pitch):
    """A cornice hood over a window: a projecting ledge, with a small pediment on top."""
    hw = width / 2 + 0.15
    b.fbox(fac, uc - hw, uc + hw, z + 0.06, z + 0.2, -0.05, 0.24, True)
    if triangle:
        outline = [(uc - hw, z + 0.2), (uc + hw, z + 0.2), (uc, z + 0.2 + hw * math.tan(pitch))]
        b.parts.solid(_prism(outline, -0.05, 0.2), True, fac.place)


def _balustrade(b, p0, p1, height):
    """Vase balusters between a plinth and a rail, along a horizontal axis-aligned line."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    length = float(np.linalg.norm(p1 - p0))
    along = (p1 - p0) / length
    across = np.array([-along[1], along[0], 0.0])
    rb = 0.12 * height
    rail = 0.12 * height

    def bar(z0, z1, half):
        c0, c1 = p0 - across * half, p1 + across * half
        b.parts.box((*np.minimum(c0, c1)[:2], z0), (*np.maximum(c0, c1)[:2], z1), True)

    z = p0[2]
    bar(z, z + rail, 1.4 * rb)
    bar(z + height - rail, z + height, 1.6 * rb)
    hb = height - 2 * rail
    t = np.linspace(0, 1, b.arc(hb / 2, np.pi, lo=3, hi=16) + 1)
    vase = np.column_stack([rb * (0.5 + 0.45 * np.sin(np.pi * t ** 1.3)), hb * t])
    vf = _lathe(np.vstack([[0, 0], vase, [0, hb]]), b.sides(rb, lo=6, hi=24))
    count = max(2, int(length / (3.5 * rb)))
    s = (np.arange(count) + 0.5) / count * length
    offsets = p0 + s[:, None] * along + [0, 0, rail]
    b.parts.solid(vf, True, offsets=offsets)


# ---------------------------------------------------------------------------------------------
# Pagoda


def _rect_ring(n_side: int):
    """Points on the unit square's boundary (|x|, |y| <= 1), counter-clockwise from (-1, -1),
    n_side per side, corners included."""
    t = 2 * np.arange(n_side) / n_side
    one = np.ones(n_side)
    x = np.concatenate([-1 + t, one, 1 - t, -one])
    y = np.concatenate([-one, -1 + t, one, 1 - t])
    return x, y


def _pagoda_roof(b, cx, cy, a, bb, z, overhang, lift, rise, top, p, q):
    """A roof with concave faces and upturned corners round a wall of half-extents (a, bb)
    whose head is at z: out to the eave, then up, curving, to the ring `top` = (half-extents)
    (the next tier's wall, or a short ridge for a hip). Returns the z where it ends."""
    # the upturn is a parabola over each half side; the slope turns by `bend` over the run
    half = min(a, bb) + overhang
    n_side = 2 * b.arc(half * half / (2 * lift + 1e-9), 2 * lift / half, lo=2, hi=24)
    run = max(overhang + min(a, bb) - min(top), 1e-3)
    bend = math.atan(rise * p / run)
    n_t = b.arc(run / max(bend, 1e-3), bend, lo=2, hi=20)
    x, y = _rect_ring(n_side)
    corner = np.minimum(np.abs(x), np.abs(y)) ** 2    # 1 at the corners, 0 mid-edge
    thick = 0.1 + 0.12 * overhang
    big_a, big_b = a + overhang, bb + overhang

    def ring(ha, hb, zz):
        return np.column_stack([cx + x * ha, cy + y * hb, np.broadcast_to(zz, x.shape)])

    rings = [ring(0.97 * a, 0.97 * bb, z - 0.5 * thick),
             ring(big_a, big_b, z + 0.35 * thick + lift * corner)]
    for t in np.linspace(0, 1, n_t + 1):
        ha = big_a - t * (big_a - top[0])
        hb = big_b - t * (big_b - top[1])
        rings.append(ring(ha, hb, z + thick + rise * t ** p + lift * corner * (1 - t) ** q))
    b.parts.solid(_loft(rings), True)
    return z + thick + rise


def _pagoda(b: _Builder):
    rng, plan = b.rng, b.plan
    cat = plan["category"]
    w, d, h = plan["width"], plan["depth"], plan["storey_h"]
    tiers = plan["storeys"] if cat == "tower" else 1 + int(rng.random() < 0.5)
    overhang = float(np.clip(rng.uniform(0.15, 0.22) * min(w, d), 0.6, 3.0))
    lift = overhang * rng.uniform(0.35, 0.6)
    p, q = rng.uniform(1.6, 2.2), rng.uniform(2.0, 3.0)
    hip = rng.uniform(0.5, 0.75)
    taper = rng.uniform(0.03, 0.06)
    finial_round = rng.random() < 0.5
    finial_rings = int(rng.integers(3, 8))
    lattice_n = int(rng.integers(3, 5))
    platform_h = rng.uniform(0.2, 0.3) * min(h, 4.0)
    margin = overhang * rng.uniform(0.7, 1.0)
    n_steps = int(rng.integers(3, 6))
    opts = _pick(rng, {"brackets": 0.75, "finial": 0.8, "lattice": 0.7, "platform": 0.7}, 2)
    z0 = platform_h if "platform" in opts else 0.0
    main, wing = _blocks(plan, z0)
    if "platform" in opts:
        for block in (main, wing):
            if block is not None:
                b.parts.box((block.x0 - margin, block.y0 - margin, 0.0),
                            (block.x1 + margin, block.y1 + margin, z0), False)
        uc, dw, _ = _Facade(main, "front").door(plan)
        x = main.x0 + uc
        tread = 0.35
        for k in range(n_steps):
            y = main.y0 - margin - (n_steps - k) * tread
            b.parts.box((x - dw, y, 0.0), (x + dw, main.y0 - margin + 0.01,
                                           z0 * (k + 1) / (n_steps + 1)), False)

    brackets = "brackets" in opts
    screens = (6 if cat == "tower" else 10) if "lattice" in opts else 0   # on front openings

    def openings(block):
        nonlocal screens
        for fac in block.facades():
            b.door(fac)
            for uc, sill, ww, wh in fac.windows(plan):
                b.panel(fac, uc, sill, ww, wh, 0.02)
                if fac.side == "front" and screens > 0:
                    screens -= 1
                    _lattice(b, fac, uc, sill, ww, wh, lattice_n)

    def roof(block_a, block_b, z, top, rise, o, per_side):
        if brackets:
            _brackets(b, block_a, block_b, z, o, per_side)
        return _pagoda_roof(b, 0.0, 0.0, block_a, block_b, z, o, lift * o / overhang, rise,
                            top, p, q)

    def hip_top(a, bb):
        ridge = 0.04 * min(a, bb)
        return (a - bb + ridge, ridge) if a >= bb else (ridge, bb - a + ridge)

    if cat == "tower":
        per_side = 2 if tiers <= 4 else 1
        for k in range(tiers):
            s = 1 - taper * k
            blk = _Block(-w / 2 * s, w / 2 * s, -d / 2 * s, d / 2 * s, z0 + k * h, 1, h,
                         plan["bays_x"], plan["bays_y"], plan["door_bay"] if k == 0 else None,
                         dict(main.hidden) if k == 0 else {},
                         [0] if k in plan["window_storeys"] else [])
            b.block_walls(blk, main=k == 0)
            openings(blk)
            a, bb = w / 2 * s, d / 2 * s
            o = overhang * s
            if k < tiers - 1:
                s1 = 1 - taper * (k + 1)
                top = (0.97 * w / 2 * s1, 0.97 * d / 2 * s1)
                roof(a, bb, blk.top, top, min(0.35 * h, 0.6 * (a + o - top[0])), o, per_side)
            else:
                apex = roof(a, bb, blk.top, hip_top(a + o, bb + o), hip * min(a, bb) + o, o,
                            per_side)
    else:
        b.block_walls(main, main=True)
        openings(main)
        a, bb = w / 2, d / 2
        per_side = 0
        if tiers == 2 and main.storeys >= 2:       # a skirt roof round the first storey
            z = main.z0 + main.storey_h
            roof(a, bb, z, (0.97 * a, 0.97 * bb), 0.6 * overhang, overhang, 1)
        if tiers == 2 and main.storeys == 1:       # a double hip: clerestory on the roof
            top = (0.6 * a, 0.6 * bb)
            roof(a, bb, main.top, top, 0.6 * (a + overhang - top[0]), overhang, per_side)
            z1 = main.top + 0.5 * h
            b.walls(-top[0], top[0], -top[1], top[1], main.top, z1)
            o = 0.7 * overhang
            apex = roof(top[0], top[1], z1, hip_top(top[0] + o, top[1] + o),
                        hip * min(top) + o, o, 1)
        else:
            apex = roof(a, bb, main.top, hip_top(a + overhang, bb + overhang),
                        hip * min(a, bb) + overhang, overhang, per_side)
    if wing is not None:
        b.block_walls(wing)
        openings(wing)
        ca, cb = (wing.x0 + wing.x1) / 2, (wing.y0 + wing.y1) / 2
        a, bb = (wing.x1 - wing.x0) / 2, (wing.y1 - wing.y0) / 2
        o = min(overhang, 0.3 * min(a, bb) + 0.3)
        if brackets:
            _brackets(b, a, bb, wing.top, o, 1, (ca, cb))
        _pagoda_roof(b, ca, cb, a, bb, wing.top, o, lift * o / overhang,
                     hip * min(a, bb) + o, hip_top(a + o, bb + o), p, q)
    if "finial" in opts:
        height = rng.uniform(0.35, 0.6) * (1.5 * h if cat == "tower" else 0.5 * min(w, d))
        _finial(b, apex, height, finial_round, finial_rings)


def _brackets(b, a, bb, z, overhang, per_side, centre=(0.0, 0.0)):
    """Clusters of stacked blocks under the eave: `per_side` on each side (0: one per bay
    division, every other one on long sides)."""
    s = 0.22 * overhang
    plan = b.plan
    for side in SIDES:
        along_x = side in ("front", "back")
        length = 2 * (a if along_x else bb)
        if per_side:
            us = np.linspace(0, length, per_side + 2)[1:-1]
        else:
            bays = plan["bays_x"] if along_x else plan["bays_y"]
            step = 1 if bays <= 6 else 2
            us = np.linspace(0, length, bays + 1)[::step]
            us = np.clip(us, 0.8 * s, length - 0.8 * s)
        blk = _Block(centre[0] - a, centre[0] + a, centre[1] - bb, centre[1] + bb, 0, 1, 1, 1, 1)
        fac = _Facade(blk, side)
        for u in us:
            b.fbox(fac, u - 0.5 * s, u + 0.5 * s, z - 2.2 * s, z - 1.4 * s, -0.05, 0.8 * s, True)
            b.fbox(fac, u - 0.4 * s, u + 0.4 * s, z - 1.4 * s, z - 0.7 * s, -0.05, 1.8 * s, True)
            b.fbox(fac, u - 1.2 * s, u + 1.2 * s, z - 0.7 * s, z + 0.05, -0.05, 2.8 * s, True)


def _lattice(b, fac, uc, sill, ww, wh, n):
    """A lattice screen in an opening: a frame and a grid of thin bars."""
    t = 0.08 * min(ww, wh)
    u0, u1, z0, z1 = uc - ww / 2, uc + ww / 2, sill, sill + wh
    for box in ((u0 - t, u0, z0 - t, z1 + t), (u1, u1 + t, z0 - t, z1 + t),
                (u0, u1, z0 - t, z0), (u0, u1, z1, z1 + t)):
        b.fbox(fac, *box, -0.05, 0.12, True)
    bar = 0.4 * t
    for u in np.linspace(u0, u1, n + 2)[1:-1]:
        b.fbox(fac, u - bar / 2, u + bar / 2, z0, z1, -0.03, 0.08, True)
    for z in np.linspace(z0, z1, n + 3)[1:-1]:
        b.fbox(fac, u0, u1, z - bar / 2, z + bar / 2, -0.03, 0.07, True)


def _finial(b, z, height, round_pole, rings):
    """A pole on the roof top with stacked discs and a jewel: round or octagonal."""
    rp = 0.03 * height
    prof = [(0, z - 0.05 * height), (3 * rp, z - 0.05 * height), (3 * rp, z + 0.06 * height),
            (rp, z + 0.1 * height)]
    for i in range(rings):
        zc = z + 0.2 * height + i * 0.5 * height / rings
        rd = rp * (3.0 - 1.2 * i / rings)
        prof += [(rp, zc), (rd, zc), (rd, zc + 0.03 * height), (rp, zc + 0.03 * height)]
    centre, rb = z + 0.86 * height, 0.07 * height          # the jewel, ending in a point
    prof += [(rp, centre - rb - 0.02 * height)]
    prof += [(rb * math.cos(t), centre + rb * math.sin(t))
             for t in np.linspace(-np.pi / 2, np.pi / 2, b.arc(rb, np.pi, lo=3) + 1)[1:-1]]
    prof += [(0, z + height)]
    n = b.sides(3 * rp, lo=12) if round_pole else 8
    b.parts.solid(_lathe(prof, n, math.pi / 8 if n == 8 else 0.0), True)


# ---------------------------------------------------------------------------------------------
# Modernist


def _modernist(b: _Builder):
    rng, plan = b.rng, b.plan
    cat = plan["category"]
    slab_o, slab_t = rng.uniform(0.3, 0.9), rng.uniform(0.2, 0.35)
    sill_f, head_f = rng.uniform(0.3, 0.4), rng.uniform(0.75, 0.85)
    mullion = rng.uniform(0.8, 1.4)
    fin_spacing, fin_depth = rng.uniform(0.6, 1.0), rng.uniform(0.4, 0.7)
    cant_slab = rng.random() < 0.4
    cant_w, cant_p = rng.uniform(0.4, 0.6), rng.uniform(0.25, 0.4)
    piloti_r = rng.uniform(0.12, 0.2)
    core = rng.uniform(0.2, 0.3)
    rail_h, tubes = rng.uniform(0.9, 1.1), int(rng.integers(2, 4))
    post_spacing = rng.uniform(1.5, 2.5)
    side_pick = rng.random(2)
    opts = _pick(rng, {"pilotis": 0.55, "cantilever": 0.55, "railing": 0.55, "fins": 0.55}, 2)
    main, wing = _blocks(plan, 0.0)
    h = main.storey_h
    free = [s for s in ("right", "back", "left") if s not in main.hidden]
    fins_side = free[int(side_pick[0] * len(free))]
    rest = [s for s in free if s != fins_side] or free
    cant_side = rest[int(side_pick[1] * len(rest))]
    lifted = "pilotis" in opts and main.storeys >= 2
    n_round = b.sides(piloti_r)

    # body
    if lifted:
        ix, iy = core * (main.x1 - main.x0), core * (main.y1 - main.y0)
        b.walls(main.x0, main.x1, main.y0, main.y1, main.z0 + h, main.top, main=True)
        b.walls(main.x0 + ix, main.x1 - ix, main.y0 + iy, main.y1 - iy, main.z0, main.z0 + h)
        core_blk = _Block(main.x0 + ix, main.x1 - ix, main.y0 + iy, main.y1 - iy, main.z0, 1,
                          h, 1, 1, 0)
        fac = _Facade(core_blk, "front")
        door = _Facade(main, "front").door(plan)
        uc = float(np.clip(door[0] - ix, door[1], fac.length - door[1]))
        b.panel(fac, uc, main.z0, door[1], door[2], 0.1)
        _pilotis(b, main, piloti_r, h, n_round)
    else:
        b.block_walls(main, main=True)
    for block in (main, wing):
        if block is None:
            continue
        if block is wing:
            b.block_walls(wing)
        b.flat_slab(block, slab_o, slab_t)
        ribbon_sides = (("front", "back", "left", "right") if cat != "tower" or block is wing
                        else ("front", "back"))
        for fac in block.facades():
            if not lifted or block is wing:
                door = b.door(fac)
            else:
                door = None
            first = 1 if (lifted and block is main) else 0
            if fac.side in ribbon_sides:
                for k in range(first, block.storeys):
                    z = block.z0 + k * block.storey_h
                    spans = [(0.03 * fac.length, 0.97 * fac.length)]
                    if k == 0 and door is not None:
                        spans = [(spans[0][0], door[0] - door[1] / 2 - 0.3),
                                 (door[0] + door[1] / 2 + 0.3, spans[0][1])]
                    for h0, h1, zt in fac.hidden:
                        if z < zt:
                            spans = [s for span in spans for s in
                                     ((span[0], min(span[1], h0 - 0.3)),
                                      (max(span[0], h1 + 0.3), span[1]))]
                    for u0, u1 in spans:
                        if u1 - u0 > 0.8:
                            _ribbon(b, fac, u0, u1, z + sill_f * block.storey_h,
                                    z + head_f * block.storey_h, mullion)
            else:
                for uc, sill, ww, wh in fac.windows(plan, range(first, block.storeys)):
                    b.panel(fac, uc, sill, ww, wh)
    if "pilotis" in opts and not lifted:         # a canopy on a row of pilotis
        depth = rng.uniform(2.0, 3.5)
        b.parts.box((main.x0 - slab_o, main.y0 - depth, main.top),
                    (main.x1 + slab_o, main.y0, main.top + slab_t), False)
        xs = np.linspace(main.x0 + 0.3, main.x1 - 0.3, main.bays_x + 1)
        y = main.y0 - depth + 0.4
        vf = _lathe([(0, 0), (piloti_r, 0), (piloti_r, main.top), (0, main.top)], n_round)
        b.parts.solid(vf, True, offsets=[(x, y, 0.0) for x in xs])
    if "cantilever" in opts:
        fac = _Facade(main, cant_side)
        perp = (main.y1 - main.y0) if fac.side in ("front", "back") else (main.x1 - main.x0)
        proj = max(1.5, cant_p * perp)
        cw = cant_w * fac.length
        u0 = (fac.length - cw) / 2
        if cant_slab:
            z = main.top - h
            b.fbox(fac, u0, u0 + cw, z - 0.2, z + 0.05, -0.3, proj, True)
        else:
            z0 = main.top - min(h, 0.6 * main.storey_h * main.storeys)
            b.fbox(fac, u0, u0 + cw, z0, main.top - 0.05, -0.3, proj, True)
    if "railing" in opts:
        _railing(b, main, slab_o, main.top + slab_t, rail_h, tubes, post_spacing)
    if "fins" in opts:
        fac = _Facade(main, fins_side)
        count = max(5, int(round(fac.length / fin_spacing)))
        for j in range(count):
            u = (j + 0.5) * fac.length / count
            if not fac.covered(u - 0.05, u + 0.05, main.z0):
                b.fbox(fac, u - 0.04, u + 0.04, main.z0 + 0.1, main.top, -0.05, fin_depth, True)


def _ribbon(b, fac, u0, u1, z_sill, z_head, spacing):
    """A continuous ribbon window: sill, glass band, head and a row of thin mullions."""
    b.fbox(fac, u0 - 0.05, u1 + 0.05, z_sill - 0.1, z_sill, -0.05, 0.2, True)
    b.fbox(fac, u0, u1, z_sill, z_head, -0.05, 0.03, True)
    b.fbox(fac, u0, u1, z_head, z_head + 0.08, -0.05, 0.1, True)
    k = max(2, int(round((u1 - u0) / spacing))) + 1
    for u in np.linspace(u0 + 0.035, u1 - 0.035, k):
        b.fbox(fac, u - 0.035, u + 0.035, z_sill, z_head, -0.05, 0.09, True)


def _pilotis(b, block, radius, height, n):
    """Thin round columns round the lifted storey (not where the wing stands)."""
    m = 0.3
    xs = np.linspace(block.x0 + m, block.x1 - m, block.bays_x + 1)
    ys = np.linspace(block.y0 + m, block.y1 - m, block.bays_y + 1)
    pts = [(x, y) for x in xs for y in (block.y0 + m, block.y1 - m)]
    pts += [(x, y) for y in ys[1:-1] for x in (block.x0 + m, block.x1 - m)]
    wing = b.plan["wing"]
    if wing is not None:
        x_side = block.x1 - m if wing["side"] > 0 else block.x0 + m
        yc = wing["offset"] * ((block.y1 - block.y0) - wing["depth"]) / 2
        pts = [(x, y) for x, y in pts
               if not (abs(x - x_side) < 1e-9 and abs(y - yc) < wing["depth"] / 2 + radius)]
    vf = _lathe([(0, 0), (radius, 0), (radius, height), (0, height)], n)
    b.parts.solid(vf, True, offsets=[(x, y, block.z0) for x, y in pts])


def _railing(b, block, overhang, z, height, tubes, spacing):
    """Posts round the roof edge with horizontal tubes between them."""
    m = overhang - 0.15
    corners = [(block.x0 - m, block.y0 - m), (block.x1 + m, block.y0 - m),
               (block.x1 + m, block.y1 + m), (block.x0 - m, block.y1 + m)]
    n = b.sides(0.035, lo=6, hi=16)
    posts = []
    for (xa, ya), (xb, yb) in zip(corners, corners[1:] + corners[:1]):
        length = math.hypot(xb - xa, yb - ya)
        k = max(1, int(math.ceil(length / spacing)))
        posts += [(xa + (xb - xa) * i / k, ya + (yb - ya) * i / k, z) for i in range(k)]
        for i in range(tubes):
            zt = z + height * (i + 1) / tubes
            b.tube((xa, ya, zt), (xb, yb, zt), 0.03, n)
    vf = _lathe([(0, 0), (0.035, 0), (0.035, height), (0, height)], n)
    b.parts.solid(vf, True, offsets=posts)


# ---------------------------------------------------------------------------------------------
# Assembly


_BUILD = {"gothic": _gothic, "classical": _classical, "pagoda": _pagoda,
          "modernist": _modernist}


def _build(style: str, plan: dict, style_seed: int, res: float) -> _Builder:
    """One building at tessellation density `res` (0 coarsest, 1 finest). The style stream
    is restarted from its seed, so only the tessellation changes with `res`."""
    b = _Builder(plan, np.random.default_rng(style_seed), res)
    _BUILD[style](b)
    return b


def _fit(style: str, plan: dict, style_seed: int, target: int):
    """The building at the finest curve density that stays below `target`, with the flat
    boxes divided to make up the rest; returns (builder, box grid step)."""
    def details(res):
        b = _build(style, plan, style_seed, res)
        return b, b.parts.count()

    best, n = details(0.0)
    if n < target:
        hi, n_hi = details(1.0)
        if n_hi <= target:
            best = hi
        else:
            lo_res, hi_res = 0.0, 1.0
            for _ in range(6):
                mid = (lo_res + hi_res) / 2
                cand, n_mid = details(mid)
                if n_mid <= target:
                    best, lo_res = cand, mid
                else:
                    hi_res = mid
    return best, best.parts.box_step(target)


def make_building(style: str, category: str, rng, name: str, n_triangles=None, scale=None,
                  yaw_deg=None):
    """`make_shape`, plus what the tests check it against: {"proportions": the body drawn
    first from `rng`, "body_corners": the top corners (4, 3) of the main wall block in the
    output frame}."""
    _check(style, STYLES, "style")
    _check(category, CATEGORIES, "category")
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    plan_seed, style_seed, place_seed = (int(s) for s in rng.integers(0, 2 ** 63 - 1, size=3))
    plan = proportions(category, np.random.default_rng(plan_seed))
    place = np.random.default_rng(place_seed)
    q_tri, q_scale, turn = place.random(), place.random(), int(place.integers(4))
    n_triangles = (int(round(_log_uniform(*TRIANGLE_RANGE, q_tri))) if n_triangles is None
                   else int(n_triangles))
    scale = float(_log_uniform(*SCALE_RANGE, q_scale)) if scale is None else float(scale)
    yaw_deg = 90.0 * turn if yaw_deg is None else float(yaw_deg)
    if not TRIANGLE_RANGE[0] <= n_triangles <= TRIANGLE_RANGE[1]:
        raise ValueError(f"n_triangles {n_triangles} outside {TRIANGLE_RANGE}")
    if not scale > 0:
        raise ValueError(f"scale {scale} must be positive")
    if yaw_deg % 90 != 0:
        raise ValueError(f"yaw_deg {yaw_deg} is not a multiple of 90")

    builder, step = _fit(style, plan, style_seed, n_triangles)
    v, f, mask = builder.parts.assemble(step)
    if not TRIANGLE_RANGE[0] <= len(f) <= TRIANGLE_RANGE[1]:
        raise RuntimeError(f"'{name}': {len(f)} triangles, outside {TRIANGLE_RANGE}")
    lo, hi = v.min(axis=0), v.max(axis=0)
    shift = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
    factor = scale / float((hi - lo).max())
    k = int(round(yaw_deg / 90)) % 4
    c, s = [(1, 0), (0, 1), (-1, 0), (0, -1)][k]
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], float)
    to_out = lambda p: ((p - shift) * factor) @ rot.T
    v = to_out(v)
    truth = {"style": style, "category": category, "face_mask": mask.astype(bool),
             "scale": scale, "yaw_deg": float(yaw_deg)}
    mesh = Mesh(name, v.astype(np.float32), f.astype(np.int32), source=SOURCE, truth=truth)
    return mesh, {"proportions": plan, "body_corners": to_out(builder.body_corners)}


def make_shape(style: str, category: str, rng, name: str, n_triangles=None, scale=None,
               yaw_deg=None) -> Mesh:
    """One building of `style` and `category`. From `rng` it draws, in this order, the seeds
    of the proportions, of the style elements and of the placement, so the same generator
    state gives the same body in every style. n_triangles, scale and yaw_deg default to
    random draws (log-uniform in TRIANGLE_RANGE and SCALE_RANGE, a multiple of 90)."""
    return make_building(style, category, rng, name, n_triangles, scale, yaw_deg)[0]


def generate(size: int = 60, seed: int = 0, styles=None, categories=None) -> list[Mesh]:
    """`size` buildings, round-robin over the (style, category) grid in a seeded order
    (60 -> 5 per cell). Triangle counts and sizes are stratified within each style from the
    same quantiles, so no style is denser or bigger on average. Names c4_NNN come from a
    random permutation and reveal nothing; the list is sorted by name."""
    styles = tuple(STYLES if styles is None else styles)
    categories = tuple(CATEGORIES if categories is None else categories)
    for s in styles:
        _check(s, STYLES, "style")
    for c in categories:
        _check(c, CATEGORIES, "category")
    if not styles or not categories:
        raise ValueError("styles and categories must not be empty")
    rng = np.random.default_rng(seed)
    cells = [(s, c) for s in styles for c in categories]
    order = rng.permutation(len(cells))
    cell = [cells[order[i % len(cells)]] for i in range(size)]
    jitter_tri, jitter_scale = rng.random(size), rng.random(size)
    n_tri, scale = np.zeros(size), np.zeros(size)
    for style in styles:
        idx = np.array([i for i in range(size) if cell[i][0] == style], int)
        k = len(idx)
        if k == 0:
            continue
        strata = np.arange(k)        # one draw per k-quantile, the same in every style
        n_tri[idx] = _log_uniform(*TRIANGLE_RANGE, (strata + jitter_tri[:k]) / k)[
            rng.permutation(k)]
        scale[idx] = _log_uniform(*SCALE_RANGE, (strata + jitter_scale[:k]) / k)[
            rng.permutation(k)]
    labels = rng.permutation(size)
    seeds = rng.integers(0, 2 ** 63 - 1, size=size)
    digits = max(3, len(str(size - 1)))
    meshes = [make_shape(s, c, np.random.default_rng(int(seeds[i])), f"c4_{labels[i]:0{digits}d}",
                         n_triangles=int(round(n_tri[i])), scale=float(scale[i]))
              for i, (s, c) in enumerate(cell)]
    return sorted(meshes, key=lambda m: m.name)
