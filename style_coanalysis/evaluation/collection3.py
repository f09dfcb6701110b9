"""collection3: curvy vs straight-lined furniture, a held-out test collection.

What it is for: checking, on shapes the analysis was never tuned on, whether the style analysis
generalises. It imitates a real user collection: 25 furniture meshes (tables, chairs, benches)
in two styles, exported from modelling tools, 9k-77k faces each, sizes from 0.4 to 600 units,
Z up, clean smooth geometry.

The spec, in short:
- STYLES = ("curvy", "straight").
  curvy: cabriole legs (S-shaped: convex knee, slender ankle, pad foot turned outward),
  scalloped aprons (lower edge cut in repeated arcs or lobes), curved crest rail and vase-shaped
  splats on chairs and benches, rounded / bullnose top and seat edges, curved arm supports.
  straight ("mission"): square straight legs (constant section or a slight straight taper),
  flat rectangular aprons, rows of vertical flat slats in backs, under arms and between
  stretchers (also on some table ends), square stretchers, square-edged tops.
- CATEGORIES = ("table", "chair", "bench"). Proportions (width, depth, heights, leg thickness,
  stretchers, arms, overhang, number of back elements, ...) come from a random stream that does
  not depend on the style: the same rng gives the same proportions in both styles, so a style
  cannot be told from proportions, only from its elements.
- Triangle count log-uniform in [9000, 77000], stratified within each style; a log-uniform size
  (largest dimension) in [0.4, 600]; a yaw in [0, 360) degrees about +Z; the shape stands on
  z = 0. Parts are separate closed solids (welded, outward-wound) that may interpenetrate.
- truth: style, category, face_mask (True on style-carrying faces: cabriole legs, scalloped
  aprons, crest rails, splats and curved arm supports for curvy; square legs and slats for
  straight), scale, yaw_deg.

This module was written from that spec alone, without reading the repository's other generators
or the analysis, so that it does not share their assumptions.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy.interpolate import PchipInterpolator

from ..meshes import Mesh

STYLES = ("curvy", "straight")
CATEGORIES = ("table", "chair", "bench")
TRI_RANGE = (9000, 77000)
SCALE_RANGE = (0.4, 600.0)
SOURCE = "collection3"


# --------------------------------------------------------------------------- primitives
# Every part is a closed surface: a subdivided cube lattice bent into shape (boxes, boards)
# or a stack of rings with end caps (tubes). Welding happens on integer lattice indices, so it
# is exact; winding is fixed afterwards from the signed volume, so any map may be used.

@lru_cache(maxsize=512)
def _lattice(nu: int, nv: int, nw: int):
    """Surface of an nu x nv x nw cube lattice: (integer node coords, outward triangles)."""
    n = (nu, nv, nw)
    pts, tris, base = [], [], 0
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        jb, jc = np.meshgrid(np.arange(n[b] + 1), np.arange(n[c] + 1), indexing="ij")
        nc = n[c] + 1
        i0 = (np.arange(n[b])[:, None] * nc + np.arange(n[c])[None, :]).ravel()
        quads = np.stack([i0, i0 + nc, i0 + nc + 1, i0 + 1], axis=1)  # normal +a
        t = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
        for side in (0, n[a]):
            p = np.empty((jb.size, 3), np.int64)
            p[:, a], p[:, b], p[:, c] = side, jb.ravel(), jc.ravel()
            pts.append(p)
            tris.append((t if side else t[:, ::-1]) + base)
            base += len(p)
    pts = np.concatenate(pts)
    lin = (pts[:, 0] * (nv + 1) + pts[:, 1]) * (nw + 1) + pts[:, 2]
    _, first, inv = np.unique(lin, return_index=True, return_inverse=True)
    uniq = pts[first]
    faces = inv.reshape(-1)[np.concatenate(tris)]
    uniq.flags.writeable = False
    faces.flags.writeable = False
    return uniq, faces


def _oriented(v: np.ndarray, f: np.ndarray):
    """(v, f) with outward winding: flip every face if the enclosed signed volume is negative."""
    p = v - v.mean(axis=0)
    vol = np.einsum("ij,ij->", p[f[:, 0]], np.cross(p[f[:, 1]], p[f[:, 2]]))
    return v, (f[:, [0, 2, 1]] if vol < 0 else f).copy()


def _solid(axes, fn):
    """The cube lattice over per-axis coordinates `axes`, mapped through fn((N,3)) -> (N,3)."""
    idx, faces = _lattice(*(len(a) - 1 for a in axes))
    pts = np.stack([axes[k][idx[:, k]] for k in range(3)], axis=1)
    return _oriented(fn(pts), faces)


def _axis(half: float, r: float, h: float) -> np.ndarray:
    """Coordinates over [-half, half] at spacing ~h, with extra rows in the rounded margins."""
    if r <= 0:
        return np.linspace(-half, half, max(1, math.ceil(2 * half / h)) + 1)
    edge = np.linspace(half - r, half, max(2, math.ceil(r * math.pi / 2 / h)) + 1)
    inner = half - r
    if inner <= 1e-9 * half:
        return np.concatenate([-edge[::-1][:-1], edge])
    mid = np.linspace(-inner, inner, max(1, math.ceil(2 * inner / h)) + 1)
    return np.concatenate([-edge[::-1], mid[1:-1], edge])


def _box(half, h, r=0.0, taper=0.0):
    """Box centred on the origin; r > 0 rounds every edge, taper narrows it towards -z."""
    half = np.asarray(half, float)
    r = min(float(r), float(half.min()))
    axes = [_axis(half[k], r, h) for k in range(3)]

    def fn(p):
        if r > 0:
            c = np.clip(p, -(half - r), half - r)
            d = p - c
            p = c + r * d / np.linalg.norm(d, axis=1, keepdims=True)
        if taper:
            s = 1.0 - taper * (half[2] - p[:, 2]) / (2 * half[2])
            p = np.column_stack([p[:, 0] * s, p[:, 1] * s, p[:, 2]])
        return p

    return _solid(axes, fn)


def _board(length, lo, hi, thick, h, plan=None, nu_min=4):
    """A board along x (centred), thickness along y, spanning z from lo(u) to hi(u), u in [0,1].

    plan(u) bends it in the y direction. Shaped edges (scallops, arches, vase outlines) are
    just lo/hi functions, so one primitive serves aprons, crests, splats and slats."""
    us = np.linspace(0.0, 1.0, max(nu_min, math.ceil(length / h)) + 1)
    span = float(np.max(hi(us) - lo(us)))
    vs = np.linspace(0.0, 1.0, max(1, math.ceil(span / h)) + 1)
    ws = np.linspace(-0.5, 0.5, max(1, math.ceil(thick / h)) + 1)

    def fn(p):
        u, v, w = p.T
        a, b = lo(u), hi(u)
        y = w * thick + (plan(u) if plan is not None else 0.0)
        return np.column_stack([(u - 0.5) * length, y, a + v * (b - a)])

    return _solid([us, vs, ws], fn)


def _tube(z, cx, cy, ax, ay, expo, n_around):
    """Stacked horizontal superellipse rings (centre cx, cy; semi-axes ax, ay) with flat caps."""
    m = len(z)
    th = 2 * np.pi * np.arange(n_around) / n_around
    c, s = np.cos(th), np.sin(th)
    e = 2.0 / np.asarray(expo, float)[:, None]
    x = cx[:, None] + ax[:, None] * np.sign(c) * np.abs(c) ** e
    y = cy[:, None] + ay[:, None] * np.sign(s) * np.abs(s) ** e
    zz = np.broadcast_to(z[:, None], x.shape)
    ring = np.column_stack([x.ravel(), y.ravel(), zz.ravel()])
    v = np.vstack([ring, [cx[0], cy[0], z[0]], [cx[-1], cy[-1], z[-1]]])
    j = np.arange(n_around)
    jn = (j + 1) % n_around
    i = np.arange(m - 1)[:, None] * n_around
    a, b = (i + j).ravel(), (i + jn).ravel()
    side = np.concatenate([np.stack([a, b, b + n_around], 1), np.stack([a, b + n_around, a + n_around], 1)])
    bot = np.stack([np.full(n_around, m * n_around), jn, j], 1)
    top = np.stack([np.full(n_around, m * n_around + 1), (m - 1) * n_around + j, (m - 1) * n_around + jn], 1)
    return _oriented(v, np.concatenate([side, bot, top]))


def _move(part, fn=None, t=(0.0, 0.0, 0.0)):
    """Apply a vertex map (may mirror; winding is re-checked) then a translation."""
    v, f = part
    v = v + np.asarray(t, float) if fn is None else fn(v) + np.asarray(t, float)
    return (v, f) if fn is None else _oriented(v, f)


def _rotz(angle):
    c, s = math.cos(angle), math.sin(angle)
    return lambda v: v @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def _span(part, p0, p1):
    """Lay a part built along local x (centred) between two horizontal points p0 -> p1."""
    d = np.subtract(p1, p0)
    mid = (np.asarray(p0, float) + np.asarray(p1, float)) / 2
    return _move(part, _rotz(math.atan2(d[1], d[0])), (mid[0], mid[1], 0.0))


def _upright(v):
    """Local x -> world z, local z -> world x (turns a board built lying down upright)."""
    return v[:, [2, 1, 0]]


# --------------------------------------------------------------------------- random draws

def _u(rng, a, b):
    return float(rng.uniform(a, b))


def _proportions(category: str, rng: np.random.Generator) -> dict:
    """Everything that is not style: drawn in a fixed order whatever the style."""
    p = {}
    if category == "table":
        p["W"] = _u(rng, 0.8, 1.8)
        p["D"] = _u(rng, 0.5, min(1.0, p["W"]))
        p["H"] = _u(rng, 0.68, 0.78)
        p["top_t"] = _u(rng, 0.025, 0.05)
        p["overhang"] = _u(rng, 0.02, 0.12)
        p["T"] = _u(rng, 0.045, 0.08)
        p["apron_h"] = _u(rng, 0.07, 0.13)
    else:
        bench = category == "bench"
        p["W"] = _u(rng, 1.0, 1.8) if bench else _u(rng, 0.42, 0.58)
        p["D"] = _u(rng, 0.38, 0.55) if bench else _u(rng, 0.42, 0.55)
        p["H"] = _u(rng, 0.40, 0.48)  # seat height
        p["top_t"] = _u(rng, 0.03, 0.05)
        p["overhang"] = _u(rng, 0.0, 0.03)
        p["T"] = _u(rng, 0.035, 0.06)
        p["apron_h"] = _u(rng, 0.06, 0.11)
    p["apron_t"] = _u(rng, 0.018, 0.026)
    p["stretchers"] = bool(rng.random() < 0.5)
    p["h_stretcher"] = bool(rng.random() < 0.5)
    p["stretcher_z"] = _u(rng, 0.10, 0.22)
    p["stretcher_T"] = p["T"] * _u(rng, 0.45, 0.6)
    p["end_panels"] = bool(rng.random() < 0.5)
    p["n_end"] = int(rng.integers(3, 7))
    p["slat_t"] = _u(rng, 0.012, 0.02)
    p["six_legs"] = category == "bench" and p["W"] > 1.45
    p["back"] = category == "chair" or (category == "bench" and bool(rng.random() < 0.75))
    p["back_h"] = _u(rng, 0.38, 0.6)
    p["lean"] = math.radians(_u(rng, 4.0, 12.0))
    p["n_back"] = int(rng.integers(7, 17)) if category == "bench" else int(rng.integers(3, 8))
    p["rail_h"] = _u(rng, 0.05, 0.09)
    p["rail_t"] = _u(rng, 0.02, 0.03)
    p["stile_T"] = p["T"] * _u(rng, 0.75, 1.0)
    p["arms"] = category != "table" and bool(rng.random() < (0.4 if category == "chair" else 0.5))
    p["arm_h"] = _u(rng, 0.2, 0.27)
    p["arm_w"] = _u(rng, 0.05, 0.09)
    p["arm_t"] = _u(rng, 0.02, 0.03)
    p["n_arm"] = int(rng.integers(2, 5))
    return p


def _style_params(style: str, rng: np.random.Generator) -> dict:
    """The style's own free choices (they never touch the proportions)."""
    if style == "straight":
        return {"taper": 0.0 if rng.random() < 0.5 else _u(rng, 0.05, 0.15),
                "slat_w": _u(rng, 0.035, 0.07)}
    return {"knee": _u(rng, 0.4, 0.6), "ankle": _u(rng, 0.08, 0.2), "foot": _u(rng, 0.3, 0.45),
            "knee_z": _u(rng, 0.72, 0.8), "r_foot": _u(rng, 0.55, 0.7),
            "r_ankle": _u(rng, 0.26, 0.32), "r_knee": _u(rng, 0.58, 0.7),
            "apron_kind": int(rng.integers(0, 2)), "lobe": _u(rng, 0.08, 0.16),
            "cut": _u(rng, 0.35, 0.6), "round": _u(rng, 0.35, 0.5),
            "arch": _u(rng, 0.3, 0.8), "bow": _u(rng, 0.01, 0.03), "ear": _u(rng, 0.1, 0.3),
            "bend": _u(rng, 0.06, 0.14), "vase": rng.uniform(-0.06, 0.06, 7),
            "splat_w": _u(rng, 0.55, 0.8), "arm_sweep": _u(rng, 0.04, 0.08)}


# --------------------------------------------------------------------------- style elements

class _Parts:
    """Collected parts: (vertices, faces, style-carrying?, group)."""

    def __init__(self):
        self.items = []

    def add(self, part, style: bool, group: str = ""):
        self.items.append((part[0], part[1], bool(style), group))


def _cabriole_profile(s: dict):
    """Centreline offset (outward, in leg thicknesses), half-size and squareness along t in [0,1]."""
    kz = s["knee_z"]
    t = [0.0, 0.035, 0.08, 0.17, 0.45, kz, 0.9, 0.94, 1.0]
    off = [s["foot"], s["foot"], 0.6 * s["foot"] - 0.1, -s["ankle"],
           -s["ankle"] + 0.3 * (s["knee"] + s["ankle"]), s["knee"], 0.12, 0.0, 0.0]
    rad = [s["r_foot"], s["r_foot"], 0.4, s["r_ankle"], 0.36, s["r_knee"], 0.52, 0.5, 0.5]
    expo = [2.2, 2.2, 2.3, 2.3, 2.5, 3.0, 6.0, 8.0, 8.0]
    return PchipInterpolator(t, off), PchipInterpolator(t, rad), PchipInterpolator(t, expo)


def _leg(style, sp, x0, y0, height, T, h):
    """One leg standing on z = 0 with its top post centred at (x0, y0); returns (part, centre(z))."""
    if style == "straight":
        part = _move(_box((T / 2, T / 2, height / 2), h, taper=sp["taper"]), t=(x0, y0, height / 2))
        return part, (lambda z: np.array([x0, y0]))
    out = np.array([np.sign(x0), np.sign(y0)], float)
    out = out / max(np.linalg.norm(out), 1e-12)
    off, rad, expo = _cabriole_profile(sp)
    n_along = max(16, math.ceil(1.5 * height / h))
    n_foot = max(4, math.ceil(0.18 * n_along))   # extra rings shape the pad foot
    t = np.unique(np.concatenate([np.linspace(0, 1, n_along + 1), np.linspace(0, 0.12, n_foot + 1)]))
    t = t[np.concatenate([[True], np.diff(t) > 0.2 / n_along])]   # no two rings (nearly) on one level
    t[-1] = 1.0
    n_around = max(12, math.ceil(2 * math.pi * sp["r_foot"] * T / h))
    r = rad(t) * T
    cx, cy = x0 + out[0] * off(t) * T, y0 + out[1] * off(t) * T
    part = _tube(t * height, cx, cy, r, r, expo(t), n_around)
    return part, (lambda z: np.array([x0, y0]) + out * float(off(z / height)) * T)


def _apron(style, sp, parts, p0, p1, z_top, height, thick, h):
    """Apron board between two leg centres; scalloped lower edge for curvy."""
    length = float(np.hypot(*np.subtract(p1, p0)))
    if style == "straight":
        part = _box((length / 2, thick / 2, height / 2), h)
        part = _move(part, t=(0, 0, z_top - height / 2))
        parts.add(_span(part, p0, p1), False)
        return
    k = max(2, round(length / sp["lobe"]))
    shallow = height * (1 - sp["cut"])
    if sp["apron_kind"] == 0:   # arcs cut upwards, meeting in points
        def depth(u):
            s = (u * k) % 1.0
            return height - (height - shallow) * np.clip(1 - (2 * s - 1) ** 2, 0, 1) ** 0.6
    else:                       # serpentine lobes hanging down
        def depth(u):
            return shallow + (height - shallow) * (0.5 + 0.5 * np.cos(2 * np.pi * k * u))
    part = _board(length, lambda u: z_top - depth(u), lambda u: np.full_like(u, z_top), thick, h,
                  nu_min=6 * k)
    parts.add(_span(part, p0, p1), True)


def _stretcher(style, parts, a, b, z, sT, h):
    """Stretcher between two leg points at height z: square bar, or a turned, slightly arched rod."""
    d = np.subtract(b, a)
    length = float(np.hypot(*d))
    if style == "straight":
        part = _move(_box((length / 2, sT / 2, sT / 2), h), t=(0, 0, z))
        parts.add(_span(part, a, b), False)
        return
    n_along = max(12, math.ceil(length / h))
    t = np.linspace(0, 1, n_along + 1)
    r = sT / 2 * (0.8 + 0.35 * np.exp(-((t - 0.5) / 0.12) ** 2)
                  + 0.25 * np.exp(-((t - 0.2) / 0.04) ** 2) + 0.25 * np.exp(-((t - 0.8) / 0.04) ** 2))
    arch = 0.04 * length * np.sin(np.pi * t)
    n_around = max(10, math.ceil(2 * math.pi * sT / h))
    part = _tube(t * length, arch, np.zeros_like(t), r, r, np.full_like(t, 2.0), n_around)
    # local z -> along the stretcher, local x -> up
    e = d / length
    R = np.array([[0.0, 0.0, 1.0], [-e[1], e[0], 0.0], [e[0], e[1], 0.0]])
    parts.add(_move(part, lambda v: v @ R, (a[0], a[1], z)), False)


def _slat_row(parts, centres, axis, z0, z1, width, thick, h):
    """Vertical flat slats (straight style) at horizontal centres, wide along `axis` ('x'/'y')."""
    for c in centres:
        hx, hy = (width / 2, thick / 2) if axis == "x" else (thick / 2, width / 2)
        part = _move(_box((hx, hy, (z1 - z0) / 2), h), t=(c[0], c[1], (z0 + z1) / 2))
        parts.add(part, True)


def _legs_and_frame(style, sp, p, parts, z_under, h):
    """Legs, aprons, stretchers and end panels under a top or seat whose underside is z_under."""
    T = p["T"]
    xl = p["W"] / 2 - p["overhang"] - T / 2
    yl = p["D"] / 2 - p["overhang"] - T / 2
    xs = [-xl, 0.0, xl] if p["six_legs"] else [-xl, xl]
    centre = {}
    for x in xs:
        for y in (-yl, yl):
            part, centre[(x, y)] = _leg(style, sp, x, y, z_under, T, h)
            parts.add(part, True)
    at = p["apron_t"]
    rec = T / 2 - at / 2 - min(0.004, 0.1 * T)
    for y in (-yl, yl):   # front and back
        yy = y + math.copysign(rec, y)
        _apron(style, sp, parts, (-xl, yy), (xl, yy), z_under, p["apron_h"], at, h)
    for x in (-xl, xl):   # ends
        xx = x + math.copysign(rec, x)
        _apron(style, sp, parts, (xx, -yl), (xx, yl), z_under, p["apron_h"], at, h)
    if not p["stretchers"]:
        return xl, yl
    z = p["stretcher_z"] * z_under / 0.7   # scaled to the leg height
    sT = p["stretcher_T"]
    mids = []
    for x in (-xl, xl):
        a, b = centre[(x, -yl)](z), centre[(x, yl)](z)
        _stretcher(style, parts, a, b, z, sT, h)
        mids.append((a + b) / 2)
    if p["h_stretcher"]:
        _stretcher(style, parts, mids[0], mids[1], z, sT, h)
    else:
        for y in (-yl, yl):
            _stretcher(style, parts, centre[(-xl, y)](z), centre[(xl, y)](z), z, sT, h)
    if style == "straight" and p["end_panels"]:
        n = p["n_end"]
        width = min(sp["slat_w"], 2 * (yl - T / 2) / (1.8 * n))
        ys = -yl + T / 2 + (2 * yl - T) * (np.arange(n) + 0.5) / n
        for x in (-xl, xl):
            _slat_row(parts, [(x, y) for y in ys], "y", z, z_under - p["apron_h"] + 0.005,
                      width, p["slat_t"], h)
    return xl, yl


def _top(style, sp, parts, W, D, z0, t, h):
    """Table top or seat: square-edged slab, or rounded / bullnose edges for curvy."""
    r = sp["round"] * t if style == "curvy" else 0.0
    parts.add(_move(_box((W / 2, D / 2, t / 2), h, r=r), t=(0, 0, z0 + t / 2)), False)


def _back(style, sp, p, parts, xl, yl, h):
    """Chair / bench back: stiles, rails and slats, or stiles, crest rail and vase splats."""
    Hs, bh, sT = p["H"], p["back_h"], p["stile_T"]
    z_bot, z_top = Hs - p["top_t"], Hs + bh
    for x in (-xl, xl):
        if style == "straight":
            stile = _box((sT / 2, sT / 2, (z_top - z_bot) / 2), h)
        else:
            n = max(12, math.ceil((z_top - z_bot) / h))
            t = np.linspace(0, 1, n + 1)
            r = sT / 2 * (1.0 - 0.2 * t)
            stile = _tube(t * (z_top - z_bot), np.zeros_like(t), np.zeros_like(t), r, r,
                          np.full_like(t, 3.0), max(12, math.ceil(4 * sT / h)))
            stile = _move(stile, t=(0, 0, -(z_top - z_bot) / 2))
        parts.add(_move(stile, t=(x, yl, (z_bot + z_top) / 2)), False, "back")
    span = 2 * xl - sT
    rh, rt = p["rail_h"], p["rail_t"]
    if style == "straight":
        top = (z_top - 0.01 - rh, z_top - 0.01)
        low = (Hs + 0.05, Hs + 0.05 + 0.7 * rh)
        for z0, z1 in (top, low):
            rail = _move(_box((xl, rt / 2, (z1 - z0) / 2), h), t=(0, yl, (z0 + z1) / 2))
            parts.add(rail, False, "back")
        n = p["n_back"]
        width = min(sp["slat_w"], span / (1.8 * n))
        xs = -span / 2 + span * (np.arange(n) + 0.5) / n
        for x in xs:
            slat = _move(_box((width / 2, p["slat_t"] / 2, (top[0] - low[1]) / 2 + 0.005), h),
                         t=(x, yl, (top[0] + low[1]) / 2))
            parts.add(slat, True, "back")
        return
    # curvy: crest rail arched on top, bowed back in plan, with ears at the ends
    zc = z_top - 0.01 - rh
    arch, ear = sp["arch"] * rh, sp["ear"] * rh
    clen = 2 * xl + 1.2 * sT

    def crest_lo(u):
        return zc + 0.6 * arch * np.sin(np.pi * u)

    def crest_hi(u):
        return zc + rh + arch * np.sin(np.pi * u) + ear * (np.exp(-(u / 0.06) ** 2) + np.exp(-((1 - u) / 0.06) ** 2))

    crest = _board(clen, crest_lo, crest_hi, rt, h, plan=lambda u: sp["bow"] * np.sin(np.pi * u), nu_min=20)
    parts.add(_move(crest, t=(0, yl, 0)), True, "back")
    shoe = _move(_box((span / 2, 0.025, 0.008), h, r=0.006), t=(0, yl, Hs + 0.008))
    parts.add(shoe, False, "back")
    n = max(1, p["n_back"] // 4)
    ws = sp["splat_w"] * min(span / n, 0.3)
    vase_t = [0.0, 0.1, 0.3, 0.55, 0.75, 0.9, 1.0]
    vase_w = np.array([0.55, 0.6, 1.0, 0.7, 0.42, 0.6, 0.75]) + sp["vase"]
    vase = PchipInterpolator(vase_t, vase_w)
    for i in range(n):
        x = -span / 2 + span * (i + 0.5) / n
        z1 = float(crest_lo((x + clen / 2) / clen)) + 0.005
        length = z1 - (Hs + 0.01)
        splat = _board(length, lambda u: -ws / 2 * vase(u), lambda u: ws / 2 * vase(u), p["slat_t"], h,
                       plan=lambda u: 0.015 * np.sin(np.pi * u), nu_min=16)
        parts.add(_move(splat, _upright, (x, yl, Hs + 0.01 + length / 2)), True, "back")


def _arms(style, sp, p, parts, xl, yl, h):
    """Arm rests over the front legs, with a square post and slats, or a curved support."""
    Hs, ah = p["H"], p["arm_h"]
    za = Hs + ah
    y_front, y_back = -yl - 0.03, yl + math.tan(p["lean"]) * ah
    L = y_back - y_front
    for x in (-xl, xl):
        if style == "straight":
            rest = _move(_box((p["arm_w"] / 2, L / 2, p["arm_t"] / 2), h),
                         t=(x, (y_front + y_back) / 2, za - p["arm_t"] / 2))
            parts.add(rest, False)
            z0 = Hs - p["top_t"]
            post = _move(_box((p["T"] / 2, p["T"] / 2, (za - z0) / 2), h), t=(x, -yl, (za + z0) / 2))
            parts.add(post, False)
            n = p["n_arm"]
            gap0, gap1 = -yl + p["T"] / 2, yl - p["stile_T"] / 2
            width = min(sp["slat_w"], (gap1 - gap0) / (1.8 * n))
            ys = gap0 + (gap1 - gap0) * (np.arange(n) + 0.5) / n
            _slat_row(parts, [(x, y) for y in ys], "y", Hs - 0.005, za - p["arm_t"] + 0.005,
                      width, p["slat_t"], h)
            continue
        sgn = math.copysign(1.0, x)
        sweep = sp["arm_sweep"]
        rest = _board(L, lambda u: np.full_like(u, -p["arm_t"]),
                      lambda u: 0.012 * np.exp(-(u / 0.12) ** 2),
                      p["arm_w"], h, plan=lambda u: 0.5 * sweep * np.sin(np.pi * u) ** 2, nu_min=16)
        # board along local x -> world y (front to back); bow outwards
        rest = _move(rest, lambda v: np.column_stack([-sgn * v[:, 1], v[:, 0], v[:, 2]]),
                     (x, (y_front + y_back) / 2, za))
        parts.add(rest, False)
        z0, z1 = Hs - p["top_t"] / 2, za - p["arm_t"] + 0.004
        n = max(12, math.ceil((z1 - z0) / h))
        t = np.linspace(0, 1, n + 1)
        cy = -yl - sweep * np.sin(np.pi * t) * (1 - 0.5 * t) + 0.5 * sweep * t ** 2
        cx = x + sgn * 0.4 * sweep * np.sin(0.5 * np.pi * t)
        r = p["T"] * (0.42 - 0.12 * np.sin(np.pi * t))
        sup = _tube(z0 + t * (z1 - z0), cx, cy, 0.8 * r, r, np.full_like(t, 2.4),
                    max(12, math.ceil(2 * math.pi * 0.4 * p["T"] / h)))
        parts.add(sup, True)


def _warp_back(style, sp, p, v):
    """Lean the back; a curvy back also curves (lumbar bulge towards the sitter)."""
    Hs, bh = p["H"], p["back_h"]
    dz = np.clip((v[:, 2] - Hs) / bh, 0.0, None)
    dy = bh * math.tan(p["lean"]) * dz
    if style == "curvy":
        dy = dy + bh * sp["bend"] * (dz ** 2 - dz)
    return np.column_stack([v[:, 0], v[:, 1] + dy, v[:, 2]])


def _build(style, category, p, sp, h) -> _Parts:
    parts = _Parts()
    z_under = p["H"] - p["top_t"]
    xl, yl = _legs_and_frame(style, sp, p, parts, z_under, h)
    _top(style, sp, parts, p["W"], p["D"], z_under, p["top_t"], h)
    if category != "table":
        if p["back"]:
            _back(style, sp, p, parts, xl, yl, h)
        if p["arms"]:
            _arms(style, sp, p, parts, xl, yl, h)
    parts.items = [(_warp_back(style, sp, p, v) if g == "back" else v, f, m, g)
                   for v, f, m, g in parts.items]
    return parts


def _count(parts: _Parts) -> int:
    return sum(len(f) for _, f, _, _ in parts.items)


# --------------------------------------------------------------------------- public API

def _log_uniform(u, lo, hi):
    return float(math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo))))


def make_shape(style: str, category: str, rng: np.random.Generator, name: str,
               n_triangles: int | None = None, scale: float | None = None,
               yaw_deg: float | None = None) -> Mesh:
    """One piece of furniture. The proportions come from a sub-stream of `rng` taken before any
    style draw, so the same rng gives the same proportions in both styles."""
    if style not in STYLES:
        raise ValueError(f"unknown style '{style}' (choose from {STYLES})")
    if category not in CATEGORIES:
        raise ValueError(f"unknown category '{category}' (choose from {CATEGORIES})")
    s_prop, s_style, s_glob = (int(x) for x in rng.integers(0, 2 ** 63, size=3))
    p = _proportions(category, np.random.default_rng(s_prop))
    sp = _style_params(style, np.random.default_rng(s_style))
    g = np.random.default_rng(s_glob)
    lo, hi = TRI_RANGE
    target = n_triangles if n_triangles is not None else _log_uniform(g.random(), lo, hi)
    target = float(np.clip(target, lo, hi))
    scale = scale if scale is not None else _log_uniform(g.random(), *SCALE_RANGE)
    yaw_deg = yaw_deg if yaw_deg is not None else float(g.uniform(0.0, 360.0))

    # Find the edge length that gives about `target` triangles (count ~ 1/h^2, plus minima).
    # Newton steps on log n against log h, slope from the last two builds (about -2).
    aim = float(np.clip(target, 1.05 * lo, 0.95 * hi))   # counts move in steps: keep clear of the ends
    band = (max(lo, 0.92 * aim), min(hi, 1.08 * aim))
    density = {"table": 12.0, "bench": 14.0, "chair": 20.0}[category]   # surface per footprint, roughly
    h = math.sqrt(density * p["W"] * p["D"] / aim)
    best, prev = None, None
    for _ in range(16):
        parts = _build(style, category, p, sp, h)
        n = _count(parts)
        if lo <= n <= hi and (best is None or abs(n - aim) < abs(_count(best) - aim)):
            best = parts
        if band[0] <= n <= band[1]:
            break
        slope = -2.0
        if prev is not None and prev[1] != n and prev[0] != h:
            slope = float(np.clip(math.log(n / prev[1]) / math.log(h / prev[0]), -3.0, -1.0))
        step = math.exp(math.log(aim / n) / slope)
        if prev is not None and n == prev[1]:
            step = 1.03 if n > aim else 1 / 1.03   # a step too small to change any count
        prev = (h, n)
        h *= step
    if best is None:
        raise RuntimeError(f"{name}: could not reach a triangle count in {TRI_RANGE}")

    verts, faces, mask, base = [], [], [], 0
    for v, f, m, _ in best.items:
        verts.append(v)
        faces.append(f + base)
        mask.append(np.full(len(f), m))
        base += len(v)
    v = np.concatenate(verts)
    f = np.concatenate(faces).astype(np.int32)
    mask = np.concatenate(mask)

    # Stand on z = 0, centre in plan, largest dimension = scale, then yaw about +Z.
    mn, mx = v.min(axis=0), v.max(axis=0)
    v = v - np.array([(mn[0] + mx[0]) / 2, (mn[1] + mx[1]) / 2, mn[2]])
    v = v * (scale / float((mx - mn).max()))
    a = math.radians(yaw_deg)
    v = _rotz(a)(v).astype(np.float32)

    # Drop any triangle that collapsed (none are expected; kept as a guard).
    w = v.astype(np.float64)
    area = 0.5 * np.linalg.norm(np.cross(w[f[:, 1]] - w[f[:, 0]], w[f[:, 2]] - w[f[:, 0]]), axis=1)
    keep = area > 1e-14 * scale * scale
    f, mask = f[keep], mask[keep]

    truth = {"style": style, "category": category, "face_mask": mask,
             "scale": float(scale), "yaw_deg": float(yaw_deg)}
    return Mesh(name, v, f, source=SOURCE, truth=truth)


def _choose(given, allowed, what):
    if given is None:
        return list(allowed)
    if isinstance(given, str):
        given = [given]
    chosen = list(dict.fromkeys(given))
    bad = [g for g in chosen if g not in allowed]
    if bad:
        raise ValueError(f"unknown {what} {bad} (choose from {allowed})")
    if not chosen:
        raise ValueError(f"no {what} chosen")
    return chosen


def _stratified(rng, k):
    """k numbers in [0, 1), one per equal stratum, in random order."""
    return (rng.permutation(k) + rng.random(k)) / k


def generate(size: int = 25, seed: int = 0, styles=None, categories=None) -> list[Mesh]:
    """`size` shapes, round-robin over the (style, category) grid visited in a seeded order.

    Triangle counts and sizes are stratified within each style, so neither style is denser or
    bigger on average. Returned sorted by name; names are a random permutation, label-free."""
    styles = _choose(styles, STYLES, "style")
    categories = _choose(categories, CATEGORIES, "category")
    if size < 0:
        raise ValueError("size must be >= 0")
    rng = np.random.default_rng([0xC3, int(seed)])
    cells = [(s, c) for s in styles for c in categories]
    order = rng.permutation(len(cells))
    labels = [cells[order[i % len(cells)]] for i in range(size)]
    tri, scale = np.empty(size), np.empty(size)
    for s in styles:
        idx = [i for i, lab in enumerate(labels) if lab[0] == s]
        for i, u in zip(idx, _stratified(rng, len(idx))):
            tri[i] = _log_uniform(u, *TRI_RANGE)
        for i, u in zip(idx, _stratified(rng, len(idx))):
            scale[i] = _log_uniform(u, *SCALE_RANGE)
    yaw = rng.uniform(0.0, 360.0, size)
    ids = rng.permutation(size)
    seeds = rng.integers(0, 2 ** 63, size)
    width = max(3, len(str(max(size - 1, 0))))
    meshes = [make_shape(s, c, np.random.default_rng(int(seeds[i])), f"c3_{ids[i]:0{width}d}",
                         n_triangles=int(round(tri[i])), scale=float(scale[i]), yaw_deg=float(yaw[i]))
              for i, (s, c) in enumerate(labels)]
    return sorted(meshes, key=lambda m: m.name)
