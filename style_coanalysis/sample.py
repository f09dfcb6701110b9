"""The sample collection: procedural furniture in four decorative styles x five categories.

Why it exists: the method needs a collection where style (decorative elements that recur across
categories) is known per shape *and* per face, so clustering purity and style localisation can be
measured. Style is carried only by ornament that shows up in 200x200 line drawings (rings on
turned posts, lattice bars with gaps, S-curved legs and scalloped edges, chamfers and
frame-and-panel steps); global proportions, part counts and triangle counts are randomised
independently of style so a global-shape baseline cannot guess it.

Everything is vectorised numpy; Z is up and every object stands on z = 0. Parts are unjoined and
may interpenetrate, like real models.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull

from .meshes import Mesh, face_areas

STYLES = ("turned", "lattice", "cabriole", "shaker")
CATEGORIES = ("chair", "table", "stool", "cabinet", "bed")

_X = np.array([1.0, 0.0, 0.0])
_Y = np.array([0.0, 1.0, 0.0])
_Z = np.array([0.0, 0.0, 1.0])


# --------------------------------------------------------------------------------------------
# primitives


def _hull(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Convex hull with outward-wound triangles (Qhull leaves winding arbitrary)."""
    hull = ConvexHull(points)
    tri = hull.simplices.copy()
    a, b, c = points[tri[:, 0]], points[tri[:, 1]], points[tri[:, 2]]
    n = np.cross(b - a, c - a)
    flip = np.einsum("ij,ij->i", n, hull.equations[:, :3]) < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    return points, tri


_SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
_CUBE_V, _CUBE_F = _hull(_SIGNS.copy())


def _loft(sections: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed solid through (n, k, 3) loops, capped by fans at both ends.

    Loops must run counter-clockwise seen from the direction of travel; the result is then
    wound outward (checked by signed volume and flipped otherwise, as a safety net).
    """
    n, k, _ = sections.shape
    verts = np.concatenate([sections.reshape(-1, 3), sections[0].mean(0)[None],
                            sections[-1].mean(0)[None]])
    i = np.arange(n - 1)[:, None]
    j = np.arange(k)[None, :]
    a = (i * k + j).ravel()
    b = (i * k + (j + 1) % k).ravel()
    c = ((i + 1) * k + (j + 1) % k).ravel()
    d = ((i + 1) * k + j).ravel()
    side = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    c0, c1 = n * k, n * k + 1
    jj = np.arange(k)
    cap0 = np.stack([np.full(k, c0), (jj + 1) % k, jj], 1)
    cap1 = np.stack([np.full(k, c1), (n - 1) * k + jj, (n - 1) * k + (jj + 1) % k], 1)
    faces = np.concatenate([side, cap0, cap1])
    if _signed_volume(verts, faces) < 0:
        faces = faces[:, [0, 2, 1]]
    return verts, faces


def _signed_volume(v: np.ndarray, f: np.ndarray) -> float:
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def _perp(d: np.ndarray) -> np.ndarray:
    ref = _X if abs(d[0]) < 0.9 else _Y
    u = ref - ref.dot(d) * d
    return u / np.linalg.norm(u)


def _tube(centres: np.ndarray, radii: np.ndarray, nseg: int, ref: np.ndarray | None = None,
          tangent: np.ndarray | None = None):
    """Circular sections of `radii` swept through `centres`; `ref` fixes the section frame."""
    if tangent is None:
        t = np.gradient(centres, axis=0)
        t /= np.linalg.norm(t, axis=1, keepdims=True)
    else:
        t = np.broadcast_to(tangent / np.linalg.norm(tangent), centres.shape)
    if ref is None:
        ref = _perp(t[0])
    u = ref[None, :] - (t @ ref)[:, None] * t
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(t, u)
    phi = np.linspace(0.0, 2 * np.pi, nseg, endpoint=False)
    ring = np.cos(phi)[None, :, None] * u[:, None] + np.sin(phi)[None, :, None] * v[:, None]
    return _loft(centres[:, None, :] + radii[:, None, None] * ring)


def _lathe(p0, p1, ts, rs, nseg: int):
    """Surface of revolution: profile radii `rs` at fractions `ts` of the axis p0 -> p1."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    axis = p1 - p0
    centres = p0[None] + np.asarray(ts, float)[:, None] * axis[None]
    return _tube(centres, np.asarray(rs, float), nseg, tangent=axis)


def _band(origin, U, V, W, xs, lo, hi, thick):
    """Extruded 2D region {lo(x) <= y <= hi(x)} in the (U, V) plane, `thick` along W.

    Enough for scalloped aprons, arched crest rails and vase-shaped splats."""
    origin = np.asarray(origin, float)
    xs, lo, hi = (np.asarray(a, float) for a in (xs, lo, hi))
    h = thick / 2.0
    quad = np.stack([np.stack([lo, -np.full_like(xs, h)], 1), np.stack([hi, -np.full_like(xs, h)], 1),
                     np.stack([hi, np.full_like(xs, h)], 1), np.stack([lo, np.full_like(xs, h)], 1)], 1)
    sec = (origin[None, None] + xs[:, None, None] * np.asarray(U)[None, None]
           + quad[..., :1] * np.asarray(V)[None, None] + quad[..., 1:] * np.asarray(W)[None, None])
    return _loft(sec)


def _chamfer_box_local(half: np.ndarray, c: float):
    """Box with all edges chamfered; top/bottom chamfers are steeper than 45 degrees so their
    inner edge is a crease at Freestyle's 134-degree threshold."""
    cx = cy = min(c, 0.45 * half[0], 0.45 * half[1])
    cz = min(1.4 * c, 0.45 * half[2])
    pts = []
    for s in _SIGNS:
        pts.append(s * [half[0], half[1] - cy, half[2] - cz])
        pts.append(s * [half[0] - cx, half[1], half[2] - cz])
        pts.append(s * [half[0] - cx, half[1] - cy, half[2]])
    return _hull(np.array(pts))


class _Parts:
    """Accumulates unjoined parts, each with a per-face decorative flag."""

    def __init__(self):
        self.v, self.f, self.m = [], [], []
        self.n = 0

    def add(self, part, deco):
        v, f = part
        self.v.append(np.asarray(v, float))
        self.f.append(f + self.n)
        self.m.append(np.broadcast_to(np.asarray(deco, bool), (len(f),)).copy())
        self.n += len(v)

    def box(self, centre, half, axes=None, chamfer=0.0, deco=False, chamfer_deco=False):
        """Oriented box; `axes` rows are its local x, y, z. Chamfer faces may count as ornament."""
        half = np.asarray(half, float)
        axes = np.eye(3) if axes is None else np.asarray(axes, float)
        if chamfer > 0:
            lv, lf = _chamfer_box_local(half, chamfer)
            fn = np.cross(lv[lf[:, 1]] - lv[lf[:, 0]], lv[lf[:, 2]] - lv[lf[:, 0]])
            fn /= np.linalg.norm(fn, axis=1, keepdims=True)
            slanted = np.abs(fn).max(1) < 0.999
            mask = np.asarray(deco) | (slanted & chamfer_deco)
        else:
            lv, lf = _CUBE_V * half, _CUBE_F
            mask = deco
        self.add((np.asarray(centre, float) + lv @ axes, lf), mask)

    def bar(self, p0, p1, width, depth_axis, depth, deco=False, chamfer=0.0, chamfer_deco=False):
        """Box from p0 to p1 (centre line), `width` across, `depth` along depth_axis."""
        p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
        d = p1 - p0
        length = np.linalg.norm(d)
        d /= length
        w = np.asarray(depth_axis, float)
        w = w - w.dot(d) * d
        w /= np.linalg.norm(w)
        s = np.cross(w, d)
        self.box((p0 + p1) / 2, [length / 2, width / 2, depth / 2], np.stack([d, s, w]),
                 chamfer=chamfer, deco=deco, chamfer_deco=chamfer_deco)

    def build(self):
        return (np.concatenate(self.v), np.concatenate(self.f).astype(np.int64),
                np.concatenate(self.m))


# --------------------------------------------------------------------------------------------
# style vocabulary


def _turned_profile(rng, n_orn=None, bulge=(1.7, 2.2)):
    """Profile (t, r/r0) of a lathe-turned post: shaft radius 1 with rings, beads and vases
    that stick out by 60-120% so they survive at 200 pixels."""
    n_orn = int(rng.integers(2, 5)) if n_orn is None else n_orn
    slots = np.linspace(0.06, 0.94, n_orn + 1)
    pts = [(0.0, 1.0)]
    for k in range(n_orn):
        a, b = slots[k], slots[k + 1]
        w = (b - a) * rng.uniform(0.35, 0.7)
        t0 = a + rng.uniform(0.1, 0.9) * ((b - a) - w)
        amp = rng.uniform(*bulge)
        kind = rng.choice(["ring", "bead", "vase", "double"])
        if kind == "ring":
            pts += [(t0, 1.0), (t0, amp), (t0 + w * 0.4, amp), (t0 + w * 0.4, 1.0)]
        elif kind == "double":
            q = w / 5
            pts += [(t0, 1.0), (t0, amp), (t0 + q, amp), (t0 + q, 1.0),
                    (t0 + 2 * q, 1.0), (t0 + 2 * q, amp * 0.85), (t0 + 3 * q, amp * 0.85),
                    (t0 + 3 * q, 1.0)]
        elif kind == "bead":
            x = np.linspace(0, 1, 5)
            pts += [(t0 + w * xi, 1.0 + (amp - 1) * np.sqrt(max(0.0, 1 - (2 * xi - 1) ** 2)))
                    for xi in x]
        else:
            x = np.linspace(0, 1, 6)
            wv = min(1.6 * w, b - t0)
            pts += [(t0 + wv * xi, 1.0 + (amp - 1) * 0.8 * np.sin(np.pi * xi) ** 2)
                    for xi in x]
    pts.append((1.0, 1.0))
    p = np.array(pts)
    p[:, 0] = np.maximum.accumulate(np.clip(p[:, 0], 0, 1))
    keep = np.r_[True, np.any(np.abs(np.diff(p, axis=0)) > 1e-9, axis=1)]  # no zero-area rings
    p = p[keep]
    return p[:, 0], p[:, 1]


class _Style:
    """One shape's draw of the style's vocabulary (sizes and counts fixed per shape, so all
    legs of one chair match while two chairs of one style differ)."""

    def __init__(self, name: str, rng: np.random.Generator):
        self.name, self.rng = name, rng
        self.nseg = int(rng.integers(9, 12))   # >= 9 sides: facets meet at > 134 degrees, no false creases
        self.profile = _turned_profile(rng, int(rng.integers(2, 4)))
        self.spindle_profile = _turned_profile(rng, int(rng.integers(1, 3)), (1.5, 1.9))
        self.knee = rng.uniform(0.07, 0.13)
        self.ankle = rng.uniform(0.03, 0.07)
        self.foot = rng.uniform(1.5, 2.0)
        self.scallops = int(rng.integers(2, 6))
        self.scallop_depth = rng.uniform(0.35, 0.6)
        self.lattice = rng.choice(["grid", "diagonal", "fret"])
        self.cell = rng.uniform(0.07, 0.11)
        self.chamfer = rng.uniform(0.25, 0.4)
        self.taper = rng.uniform(0.5, 0.75)
        self.back_kind = rng.choice(["slats", "panel"])

    # -- legs ------------------------------------------------------------------------------
    def leg(self, P: _Parts, top, height, thick, outward):
        """A leg from `top` (x, y, z) down to z = 0; `outward` is the horizontal unit vector
        from the piece's centre towards this corner."""
        top = np.asarray(top, float)
        bottom = np.array([top[0], top[1], top[2] - height])
        if self.name == "turned":
            ts, rs = self.profile
            P.add(_lathe(bottom, top, ts, rs * thick / 2, self.nseg), True)
        elif self.name == "cabriole":
            self._cabriole(P, top, height, thick, outward)
        elif self.name == "shaker":
            h = thick / 2
            b = h * self.taper
            pts = np.array([[sx * h, sy * h, 0.0] for sx in (-1, 1) for sy in (-1, 1)]
                           + [[sx * b, sy * b, -height] for sx in (-1, 1) for sy in (-1, 1)])
            P.add(_hull(top + pts), False)
        else:  # lattice: plain square legs, the ornament is in the panels
            P.box(top - [0, 0, height / 2], [thick / 2, thick / 2, height / 2])

    def _cabriole(self, P, top, height, thick, outward):
        o = np.array([outward[0], outward[1], 0.0])
        o /= np.linalg.norm(o)
        s = np.linspace(0.0, 1.0, 14)
        lift = 0.10
        knee = self.knee * height * np.sin(np.pi * np.clip(s / 0.4, 0, 1))
        ankle = -self.ankle * height * np.sin(np.pi * np.clip((s - 0.4) / 0.5, 0, 1))
        off = knee + ankle
        z = top[2] - s * (height * (1 - lift) - thick * 0.3)
        centres = np.stack([top[0] + off * o[0], top[1] + off * o[1], z], 1)
        r = thick / 2 * np.interp(s, [0, 0.25, 0.85, 1.0], [1.0, 1.15, 0.5, 0.6])
        P.add(_tube(centres[::-1], r[::-1], self.nseg, ref=np.cross(_Z, o)), True)
        # pad ("scroll") foot: a flattened bulb turned outward
        fr = thick / 2 * self.foot
        fts = np.array([0.0, 0.15, 0.5, 0.85, 1.0])
        frs = fr * np.array([0.6, 0.95, 1.0, 0.8, 0.35])
        base = np.array([top[0] + 0.02 * height * o[0], top[1] + 0.02 * height * o[1], 0.0])
        P.add(_lathe(base, base + [0, 0, height * lift + 0.3 * thick], fts, frs, self.nseg), True)

    # -- rails between legs ------------------------------------------------------------------
    def apron(self, P, p0, p1, height, thick, out_axis):
        """A rail hanging below a top between two leg tops p0 and p1 (same z)."""
        p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
        U = p1 - p0
        L = np.linalg.norm(U)
        U /= L
        if self.name == "cabriole":
            xs = np.linspace(0, L, 8 * self.scallops + 1)
            ph = np.abs(np.sin(np.pi * self.scallops * xs / L))
            lo = -height * (1 - self.scallop_depth * ph)
            P.add(_band(p0, U, _Z, out_axis, xs, lo, np.zeros_like(xs), thick), True)
        elif self.name == "lattice":   # at least two cells tall, or the bars hide in the frame
            height = max(height, 2.2 * self.cell)
            self.panel(P, p0 - [0, 0, height], U, _Z, out_axis, L, height, thick, "apron")
        elif self.name == "turned":
            P.bar(p0 - [0, 0, height * 0.35], p1 - [0, 0, height * 0.35], height * 0.7,
                  out_axis, thick)
            ts, rs = self.spindle_profile
            zz = [0, 0, height * 1.1]
            P.add(_lathe(p0 - zz, p1 - zz, ts, rs * thick * 0.45, self.nseg), True)
        else:
            P.bar(p0 - [0, 0, height / 2], p1 - [0, 0, height / 2], height, out_axis, thick,
                  chamfer=thick * self.chamfer, chamfer_deco=True)

    def stretcher(self, P, p0, p1, thick):
        """Low rail between two legs; cabriole pieces have none (their legs splay)."""
        if self.name == "turned":
            ts, rs = self.spindle_profile
            P.add(_lathe(p0, p1, ts, rs * thick / 2, self.nseg), True)
        elif self.name in ("lattice", "shaker"):
            P.bar(p0, p1, thick, _Z, thick)

    # -- panels ----------------------------------------------------------------------------
    def panel(self, P, origin, U, V, W, width, height, thick, kind="back"):
        """Fill the rectangle origin + [0,width]U + [0,height]V (thickness along W)."""
        origin = np.asarray(origin, float)
        U, V, W = (np.asarray(a, float) for a in (U, V, W))
        fw = min(width, height) * 0.09 + 0.01   # frame rail width

        def at(x, y):
            return origin + x * U + y * V

        if self.name == "lattice":
            self._frame(P, at, width, height, fw, W, thick, True)
            self._lattice(P, at, width, height, fw, W, thick * 0.7)
            if kind == "door":
                P.box(at(width / 2, height / 2) - W * thick * 0.6,
                      [width / 2, height / 2, thick * 0.2], np.stack([U, V, W]))
        elif self.name == "turned":
            rail = max(fw, 0.03)
            P.bar(at(0, height - rail / 2), at(width, height - rail / 2), rail, W, thick)
            P.bar(at(0, rail / 2), at(width, rail / 2), rail, W, thick)
            if kind == "door":
                P.box(at(width / 2, height / 2) - W * thick * 0.5,
                      [width / 2, height / 2, thick * 0.25], np.stack([U, V, W]))
            n = int(np.clip(round(width / (self.cell * 1.4)), 2, 6))
            ts, rs = self.spindle_profile
            r = min(width / n * 0.18, 0.03)
            for x in (np.arange(n) + 0.5) * width / n:
                P.add(_lathe(at(x, rail * 0.5), at(x, height - rail * 0.5), ts, rs * r,
                             self.nseg), True)
        elif self.name == "cabriole":
            self._cabriole_panel(P, at, U, V, W, width, height, thick, kind)
        else:
            self._frame(P, at, width, height, fw, W, thick, True, chamfer=True)
            if kind == "back" and self.back_kind == "slats":
                n = int(self.rng.integers(2, 5))
                for y in np.linspace(fw, height - fw, n + 2)[1:-1]:
                    P.bar(at(0, y), at(width, y), fw * 1.3, W, thick * 0.8,
                          chamfer=thick * 0.25, chamfer_deco=True)
            else:
                P.box(at(width / 2, height / 2) - W * thick * 0.25,
                      [width / 2 - fw / 2, height / 2 - fw / 2, thick * 0.2], np.stack([U, V, W]),
                      deco=True)

    def _frame(self, P, at, width, height, fw, W, thick, deco, chamfer=False):
        c = thick * self.chamfer if chamfer else 0.0
        for a, b in (((0, fw / 2), (width, fw / 2)), ((0, height - fw / 2), (width, height - fw / 2)),
                     ((fw / 2, 0), (fw / 2, height)), ((width - fw / 2, 0), (width - fw / 2, height))):
            P.bar(at(*a), at(*b), fw, W, thick, deco=deco and not chamfer, chamfer=c,
                  chamfer_deco=True)

    def _lattice(self, P, at, width, height, fw, W, depth):
        """Thin bars with open gaps: orthogonal grid, diagonal trellis or broken fretwork."""
        cell = self.cell
        bw = cell * 0.22
        x0, x1, y0, y1 = fw * 0.5, width - fw * 0.5, fw * 0.5, height - fw * 0.5
        nx = max(1, int(round((x1 - x0) / cell)))
        ny = max(1, int(round((y1 - y0) / cell)))
        xs = np.linspace(x0, x1, nx + 1)[1:-1]
        ys = np.linspace(y0, y1, ny + 1)[1:-1]
        if self.lattice == "grid":
            for x in xs:
                P.bar(at(x, y0), at(x, y1), bw, W, depth, deco=True)
            for y in ys:
                P.bar(at(x0, y), at(x1, y), bw, W, depth, deco=True)
        elif self.lattice == "fret":
            gx = np.linspace(x0, x1, nx + 1)
            gy = np.linspace(y0, y1, ny + 1)
            for x in xs:  # vertical segments, some left out -> stepped fretwork
                for k in range(ny):
                    if self.rng.random() < 0.65:
                        P.bar(at(x, gy[k] - bw / 2), at(x, gy[k + 1] + bw / 2), bw, W, depth, True)
            for y in ys:
                for k in range(nx):
                    if self.rng.random() < 0.65:
                        P.bar(at(gx[k] - bw / 2, y), at(gx[k + 1] + bw / 2, y), bw, W, depth, True)
        else:
            step = cell * 1.2
            for sgn in (1.0, -1.0):
                for c in np.arange(-(x1 - x0), (y1 - y0) + (x1 - x0), step)[1:]:
                    seg = _clip_diagonal(c, sgn, x0, x1, y0, y1)
                    if seg is not None:
                        P.bar(at(*seg[0]), at(*seg[1]), bw, W, depth, deco=True)

    def _cabriole_panel(self, P, at, U, V, W, width, height, thick, kind):
        """Serpentine crest rail with an arched top, and a vase-shaped splat (backs) or an
        arched, scalloped door panel."""
        crest = min(0.25 * height, 0.09 + 0.05 * self.rng.random())
        xs = np.linspace(0, width, 31)
        arch = crest * 0.9 * np.sin(np.pi * xs / width) ** 2
        ph = np.abs(np.sin(np.pi * self.scallops * xs / width))
        lo = np.full_like(xs, height - crest) - crest * 0.35 * ph
        P.add(_band(at(0, 0), U, V, W, xs, lo, height + arch, thick), True)
        if kind == "door":
            P.box(at(width / 2, (height - crest) / 2), [width / 2, (height - crest) / 2, thick * 0.3],
                  np.stack([U, V, W]))
            ys = np.linspace(0, height - crest, 21)
            half = width * 0.36
            bulge = half * (0.55 + 0.45 * np.clip(np.sin(np.pi * ys / (height - crest)), 0, 1) ** 0.6)
            P.add(_band(at(width / 2, 0) + W * thick * 0.2, V, -U, W, ys, -bulge, bulge,
                        thick * 0.3), True)
        else:
            ys = np.linspace(0, height - crest * 0.9, 25)
            s = ys / ys[-1]
            half = width * (0.1 + 0.13 * np.sin(np.pi * np.clip(s * 1.25, 0, 1)) ** 2
                            + 0.05 * s)
            P.add(_band(at(width / 2, 0), V, -U, W, ys, -half, half, thick * 0.7), True)
            P.bar(at(0, crest * 0.4), at(width, crest * 0.4), crest * 0.8, W, thick)


def _clip_diagonal(c, sgn, x0, x1, y0, y1):
    """Segment of the line y - y0 = sgn*(x - x0) + c inside the rectangle, or None."""
    ts = []
    for x in (x0, x1):
        y = y0 + sgn * (x - x0) + c
        if y0 <= y <= y1:
            ts.append((x, y))
    for y in (y0, y1):
        x = x0 + (y - y0 - c) / sgn
        if x0 <= x <= x1:
            ts.append((x, y))
    if len(ts) < 2:
        return None
    ts = sorted(set((round(a, 9), round(b, 9)) for a, b in ts))
    a, b = np.array(ts[0]), np.array(ts[-1])
    if np.linalg.norm(b - a) < 1e-3:
        return None
    return a, b


# --------------------------------------------------------------------------------------------
# categories


def _legs_and_top(P, S, rng, w, d, h, top_t, leg_t, inset, apron_h, stretch_p):
    """Four legs under a rectangular top (w x d at height h), with aprons and stretchers."""
    if S.name == "lattice" and apron_h <= 0:   # plain legs: the lattice must show somewhere
        apron_h = rng.uniform(0.06, 0.1)
    corners = np.array([[sx * (w / 2 - inset), sy * (d / 2 - inset)]
                        for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
    z = h - top_t
    for cx, cy in corners:
        S.leg(P, [cx, cy, z], z, leg_t, [np.sign(cx), np.sign(cy)])
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        mid = (a + b) / 2
        out = np.array([mid[0], mid[1], 0.0])
        out = out / np.linalg.norm(out)
        if apron_h > 0:
            S.apron(P, [*a, z], [*b, z], apron_h, leg_t * 0.5, out)
        if rng.random() < stretch_p:
            zz = z * rng.uniform(0.2, 0.35)
            S.stretcher(P, [*a, zz], [*b, zz], leg_t * 0.55)
    chamfer = top_t * S.chamfer if S.name == "shaker" else 0.0
    P.box([0, 0, h - top_t / 2], [w / 2, d / 2, top_t / 2], chamfer=chamfer, chamfer_deco=True)
    if rng.random() < 0.35:   # plain low shelf, any style: varies area and structure, not style
        hw, hd = abs(corners[0][0]), abs(corners[0][1])
        P.box([0, 0, z * rng.uniform(0.12, 0.3)], [hw, hd, 0.01])
    return corners


def _chair(P, S, rng):
    w, d = rng.uniform(0.4, 0.55), rng.uniform(0.4, 0.55)
    h = rng.uniform(0.42, 0.5)
    leg_t = rng.uniform(0.04, 0.055)
    corners = _legs_and_top(P, S, rng, w, d, h, rng.uniform(0.03, 0.05), leg_t, leg_t / 2,
                            rng.uniform(0.06, 0.1) * rng.integers(0, 2), 0.6)
    back_h = rng.uniform(0.35, 0.6)
    yb = corners[0][1]
    post = leg_t * 0.9
    for x in (corners[0][0], corners[1][0]):
        base = np.array([x, yb, h])
        if S.name == "turned":
            ts, rs = S.profile
            P.add(_lathe(base, base + [0, 0, back_h], ts, rs * post / 2, S.nseg), True)
        else:
            P.box(base + [0, 0, back_h / 2], [post / 2, post / 2, back_h / 2])
    if rng.random() < 0.35:   # plain arm rests, any style
        arm_z = h + rng.uniform(0.18, 0.25)
        for x in (corners[0][0], corners[1][0]):
            P.box([x, 0, arm_z], [0.02, d / 2, 0.015])
            P.box([x, corners[2][1], (h + arm_z) / 2], [0.015, 0.015, (arm_z - h) / 2])
    x0 = corners[0][0] + post / 2
    S.panel(P, [x0, yb, h + 0.04], _X, _Z, -_Y, corners[1][0] - post / 2 - x0,
            back_h - 0.04, post * 0.6, "back")


def _table(P, S, rng):
    w, d = rng.uniform(0.8, 1.5), rng.uniform(0.5, 0.9)
    h = rng.uniform(0.68, 0.78)
    leg_t = rng.uniform(0.05, 0.07)
    _legs_and_top(P, S, rng, w, d, h, rng.uniform(0.03, 0.05), leg_t,
                  rng.uniform(0.03, 0.08), rng.uniform(0.08, 0.13), 0.5)


def _stool(P, S, rng):
    s = rng.uniform(0.3, 0.45)
    h = rng.uniform(0.42, 0.75)
    leg_t = rng.uniform(0.04, 0.055)
    _legs_and_top(P, S, rng, s * rng.uniform(0.85, 1.15), s, h, rng.uniform(0.03, 0.05), leg_t,
                  rng.uniform(0.01, 0.04), rng.uniform(0.05, 0.09) * rng.integers(0, 2), 0.8)


def _cabinet(P, S, rng):
    w, d = rng.uniform(0.5, 1.0), rng.uniform(0.35, 0.5)
    H = rng.uniform(0.8, 1.6)
    foot = rng.uniform(0.1, 0.25) * (1.6 if S.name == "cabriole" else 1.0)
    t = 0.02
    body_h = H - foot
    # carcass: sides, back, bottom, top (top overhangs; shaker chamfers it)
    P.box([-w / 2 + t / 2, 0, foot + body_h / 2], [t / 2, d / 2, body_h / 2])
    P.box([w / 2 - t / 2, 0, foot + body_h / 2], [t / 2, d / 2, body_h / 2])
    P.box([0, d / 2 - t / 2, foot + body_h / 2], [w / 2, t / 2, body_h / 2])
    P.box([0, 0, foot + t / 2], [w / 2, d / 2, t / 2])
    ot = rng.uniform(0.025, 0.05)
    chamfer = ot * S.chamfer if S.name == "shaker" else 0.0
    P.box([0, 0, H + ot / 2 - t], [w / 2 + 0.02, d / 2 + 0.02, ot / 2], chamfer=chamfer,
          chamfer_deco=True)
    leg_t = rng.uniform(0.05, 0.07)
    for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        x, y = sx * (w / 2 - leg_t / 2), sy * (d / 2 - leg_t / 2)
        if S.name == "lattice":   # plinth-like block feet
            P.box([x, y, foot / 2], [leg_t / 2, leg_t / 2, foot / 2])
        else:
            S.leg(P, [x, y, foot + 0.01], foot + 0.01, leg_t, [sx, sy])
    if S.name in ("cabriole", "shaker", "lattice"):
        S.apron(P, [-w / 2, -d / 2 - 0.005, foot], [w / 2, -d / 2 - 0.005, foot],
                min(0.08, foot * 0.6), 0.02, -_Y)
    # doors on the front
    n_doors = int(rng.integers(1, 3)) if w < 0.8 else 2
    n_rows = int(rng.integers(1, 3)) if body_h > 1.0 else 1
    dw, dh = (w - 2 * t) / n_doors, (body_h - 2 * t) / n_rows
    for i in range(n_doors):
        for j in range(n_rows):
            S.panel(P, [-w / 2 + t + i * dw + 0.005, -d / 2, foot + t + j * dh + 0.005], _X, _Z,
                    -_Y, dw - 0.01, dh - 0.01, 0.02, "door")
    if S.name == "turned":   # turned half-columns on the front corners
        ts, rs = S.profile
        for sx in (-1, 1):
            base = np.array([sx * (w / 2 - 0.01), -d / 2 - 0.01, foot])
            P.add(_lathe(base, base + [0, 0, body_h], ts, rs * 0.018, S.nseg), True)


def _bed(P, S, rng):
    w, L = rng.uniform(0.9, 1.8), rng.uniform(1.8, 2.1)
    rail_h = rng.uniform(0.25, 0.4)
    head_h = rng.uniform(0.45, 0.9)
    foot_h = rng.uniform(0.2, 0.5) if rng.random() < 0.6 else 0.0
    post_t = rng.uniform(0.06, 0.09)
    # mattress platform and side rails
    P.box([0, 0, rail_h - 0.05], [w / 2 - post_t / 2, L / 2 - post_t / 2, 0.05])
    for sx in (-1, 1):
        P.box([sx * (w / 2 - post_t / 2), 0, rail_h - 0.1], [0.015, L / 2, 0.08])
    mat = rng.uniform(0.1, 0.22)
    P.box([0, 0.05, rail_h + mat / 2], [w / 2 - post_t, L / 2 - post_t - 0.05, mat / 2])
    for end, top in ((1, head_h), (-1, foot_h)):
        y = end * (L / 2 - post_t / 2)
        post_h = rail_h + top + (0.1 if top > 0 else 0.0)
        for sx in (-1, 1):
            x = sx * (w / 2 - post_t / 2)
            if S.name == "cabriole":
                S.leg(P, [x, y, rail_h], rail_h, post_t, [sx, end])
                if top > 0:
                    P.box([x, y, rail_h + top / 2], [post_t / 3, post_t / 3, top / 2])
            else:
                S.leg(P, [x, y, post_h], post_h, post_t, [sx, end])
        if top > 0.1:
            x0 = -w / 2 + post_t
            S.panel(P, [x0, y, rail_h + 0.02], _X, _Z, -_Y if end < 0 else _Y,
                    w - 2 * post_t, top - 0.02, post_t * 0.5, "back")
    if S.name in ("cabriole", "lattice", "shaker") and rng.random() < 0.7:
        for sx in (-1, 1):   # aprons along the sides, under the rail
            S.apron(P, [sx * (w / 2 + 0.005), -L / 2 + post_t, rail_h - 0.12],
                    [sx * (w / 2 + 0.005), L / 2 - post_t, rail_h - 0.12],
                    min(0.1, rail_h * 0.4), 0.02, np.array([sx, 0.0, 0.0]))


_BUILDERS = {"chair": _chair, "table": _table, "stool": _stool, "cabinet": _cabinet, "bed": _bed}


# --------------------------------------------------------------------------------------------
# tessellation: decouple triangle count from style


def _pad_faces(v, f, m, target, rng):
    """Split the largest triangles at their centroids until `target` faces: the surface and
    its creases are unchanged, only the triangle count (which would otherwise betray style)."""
    while len(f) < target:
        k = min(len(f), (target - len(f) + 1) // 2)
        areas = face_areas(v, f)
        # prefer large faces, with randomness so flat parts are not split in a fixed order
        pick = np.argsort(-areas * rng.uniform(0.5, 1.0, len(f)))[:k]
        tri = f[pick]
        g = np.arange(len(v), len(v) + k)
        v = np.concatenate([v, v[tri].mean(axis=1)])
        new = np.concatenate([np.stack([tri[:, 1], tri[:, 2], g], 1),
                              np.stack([tri[:, 2], tri[:, 0], g], 1)])
        f = f.copy()
        f[pick] = np.stack([tri[:, 0], tri[:, 1], g], 1)
        f = np.concatenate([f, new])
        m = np.concatenate([m, m[pick], m[pick]])
    return v, f, m


def make_shape(style: str, category: str, seed, name: str | None = None,
               face_range=(3000, 8000)) -> Mesh:
    """One piece of furniture; same (style, category, seed) -> identical arrays."""
    rng = np.random.default_rng(seed)
    S = _Style(style, rng)
    P = _Parts()
    _BUILDERS[category](P, S, rng)
    v, f, m = P.build()
    v, f, m = _pad_faces(v, f, m, int(rng.integers(*face_range)), rng)
    v[:, 2] -= v[:, 2].min()
    name = name or f"{category}_{style}"
    return Mesh(name, v.astype(np.float32), f.astype(np.int32), source="sample",
                truth={"style": style, "category": category, "face_mask": m})


def generate(size: int = 120, seed: int = 0) -> list[Mesh]:
    """Balanced collection: style x category combinations cycled, in a seeded shuffled order."""
    combos = [(s, c) for c in CATEGORIES for s in STYLES]
    order = np.random.default_rng(seed).permutation(len(combos))
    counters: dict = {}
    out = []
    for i in range(size):
        style, cat = combos[order[i % len(combos)]]
        k = counters.get((style, cat), 0)
        counters[(style, cat)] = k + 1
        out.append(make_shape(style, cat, [seed, i], f"{cat}_{style}_{k:03d}"))
    return out
