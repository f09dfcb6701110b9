"""Collection 4 (procedural buildings in four styles): the geometry is sound, the ground truth
and the placement are as specified, the proportions do not depend on the style, and each
style's own marker elements are there."""
import math
import re

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from style_coanalysis.evaluation import collection4 as c4
from style_coanalysis.meshes import face_areas, validate


@pytest.fixture(scope="module")
def shapes():
    return c4.generate(12, seed=0)


def _parts(mesh):
    """Connected components: list of (vertex ids, face ids)."""
    f = mesh.faces.astype(np.int64)
    n = len(mesh.vertices)
    g = coo_matrix((np.ones(2 * len(f)), (np.r_[f[:, 0], f[:, 1]], np.r_[f[:, 1], f[:, 2]])),
                   shape=(n, n))
    _, label = connected_components(g, directed=False)
    face_label = label[f[:, 0]]
    v_order, f_order = np.argsort(label, kind="stable"), np.argsort(face_label, kind="stable")
    v_split = np.split(v_order, np.flatnonzero(np.diff(label[v_order])) + 1)
    f_split = np.split(f_order, np.flatnonzero(np.diff(face_label[f_order])) + 1)
    return list(zip(v_split, f_split))


def _style_parts(mesh, style=True):
    mask = mesh.truth["face_mask"]
    v = mesh.vertices.astype(np.float64)
    return [v[vi] for vi, fi in _parts(mesh) if mask[fi[0]] == style]


def _of(shapes, style):
    return [m for m in shapes if m.truth["style"] == style]


# ------------------------------------------------------------------------ geometry and truth


def test_every_cell_once(shapes):
    cells = {(m.truth["style"], m.truth["category"]) for m in shapes}
    assert cells == {(s, c) for s in c4.STYLES for c in c4.CATEGORIES}


def test_meshes_validate_and_parts_are_closed_outward_solids(shapes):
    for m in shapes:
        validate(m)
        assert m.vertices.dtype == np.float32 and m.faces.dtype == np.int32
        assert m.source == c4.SOURCE
        f = m.faces.astype(np.int64)
        n = len(m.vertices)
        directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        key = directed[:, 0] * n + directed[:, 1]
        assert len(np.unique(key)) == len(key), f"{m.name}: an edge is used twice one way"
        assert np.isin(directed[:, 1] * n + directed[:, 0], key).all(), f"{m.name}: open edge"
        assert (face_areas(m.vertices, m.faces) > 0).all(), f"{m.name}: degenerate triangle"
        v = m.vertices.astype(np.float64)
        for vi, fi in _parts(m):
            assert len(np.unique(v[vi], axis=0)) == len(vi), f"{m.name}: unwelded part"
            a, b, c = (v[f[fi, k]] - v[vi].mean(axis=0) for k in range(3))
            assert np.einsum("ij,ij->i", a, np.cross(b, c)).sum() > 0, f"{m.name}: inward part"


def test_triangle_counts(shapes):
    for m in shapes:
        assert c4.TRIANGLE_RANGE[0] <= len(m.faces) <= c4.TRIANGLE_RANGE[1]
    for style in c4.STYLES:
        for target in (4500, 25000):
            m = c4.make_shape(style, "house", np.random.default_rng(3), "x", n_triangles=target)
            assert abs(len(m.faces) / target - 1) <= 0.15, (style, target, len(m.faces))


def test_placement(shapes):
    for m in shapes:
        v = m.vertices.astype(np.float64)
        lo, hi = v.min(axis=0), v.max(axis=0)
        scale = m.truth["scale"]
        assert c4.SCALE_RANGE[0] <= scale <= c4.SCALE_RANGE[1]
        assert math.isclose((hi - lo).max(), scale, rel_tol=1e-5)
        assert abs(lo[2]) <= 1e-6 * scale
        assert np.all(np.abs(lo[:2] + hi[:2]) / 2 <= 1e-5 * scale)
        assert m.truth["yaw_deg"] % 90 == 0
    assert len({m.truth["yaw_deg"] % 360 for m in shapes}) > 1


def test_truth_and_style_faces(shapes):
    for m in shapes:
        t = m.truth
        assert {"style", "category", "face_mask", "scale", "yaw_deg"} <= set(t)
        assert t["style"] in c4.STYLES and t["category"] in c4.CATEGORIES
        mask = t["face_mask"]
        assert mask.dtype == bool and mask.shape == (len(m.faces),)
        assert 0 < mask.sum() < len(mask), f"{m.name} lacks style or plain faces"
        for _, fi in _parts(m):       # a part is style-carrying as a whole or not at all
            assert mask[fi].all() or not mask[fi].any()


def test_deterministic_and_seeded(shapes):
    again = c4.generate(12, seed=0)
    assert [m.name for m in again] == [m.name for m in shapes]
    for a, b in zip(shapes, again):
        assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
        assert np.array_equal(a.truth["face_mask"], b.truth["face_mask"])
    other = c4.generate(12, seed=1)
    assert any(len(a.faces) != len(b.faces) for a, b in zip(shapes, other))


def test_names_reveal_nothing(shapes):
    names = [m.name for m in shapes]
    assert names == sorted(names)
    assert set(names) == {f"c4_{i:03d}" for i in range(12)}
    words = c4.STYLES + c4.CATEGORIES
    assert all(re.fullmatch(r"c4_\d+", n) and not any(w in n for w in words) for n in names)


def test_sizes_and_densities_are_stratified_alike_in_every_style():
    shapes = c4.generate(8, seed=3, categories=("hall",))      # 2 per style
    scales = {s: sorted(m.truth["scale"] for m in _of(shapes, s)) for s in c4.STYLES}
    for s in c4.STYLES:
        assert np.allclose(scales[s], scales["gothic"])
    means = [np.exp(np.mean(np.log([len(m.faces) for m in _of(shapes, s)]))) for s in c4.STYLES]
    assert max(means) / min(means) < 1.3


def test_bad_names_raise():
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="baroque"):
        c4.make_shape("baroque", "house", rng, "x")
    with pytest.raises(ValueError, match="castle"):
        c4.make_shape("gothic", "castle", rng, "x")
    with pytest.raises(ValueError, match="rococo"):
        c4.generate(4, styles=("gothic", "rococo"))
    with pytest.raises(ValueError, match="barn"):
        c4.generate(4, categories=("barn",))


# ------------------------------------------------------------------------ proportions


def test_same_stream_same_body_in_every_style():
    for category in c4.CATEGORIES:
        plans, ratios = [], []
        for style in c4.STYLES:
            mesh, info = c4.make_building(style, category, np.random.default_rng(11), "x")
            plans.append(info["proportions"])
            corners = info["body_corners"]
            v = mesh.vertices.astype(np.float64)
            plain = np.unique(mesh.faces[~mesh.truth["face_mask"]])
            near = np.linalg.norm(v[plain][None] - corners[:, None], axis=2).min(axis=1)
            assert near.max() <= 1e-5 * mesh.truth["scale"], (style, category)
            sides = np.linalg.norm(np.roll(corners, -1, axis=0) - corners, axis=1)
            ratios.append(sides[0] / sides[1])
        assert all(p == plans[0] for p in plans), category
        assert np.allclose(ratios, plans[0]["width"] / plans[0]["depth"], rtol=1e-4)


def test_category_proportions(shapes):
    for seed in range(100):
        rng = np.random.default_rng(seed)
        house, tower, hall = (c4.proportions(c, rng) for c in c4.CATEGORIES)
        assert house["storeys"] in (1, 2, 3)
        assert 1.0 <= max(house["width"], house["depth"]) / min(house["width"],
                                                                 house["depth"]) <= 1.6
        height = tower["storeys"] * tower["storey_h"]
        assert 3 <= tower["storeys"] <= 7
        assert 2.5 <= height / min(tower["width"], tower["depth"])
        assert height / max(tower["width"], tower["depth"]) <= 5.0
        assert hall["storeys"] == 1 and 2.5 <= hall["depth"] / hall["width"] <= 4.0
    for m in shapes:
        ext = np.ptp(m.vertices.astype(np.float64), axis=0)
        plan_long, plan_short = max(ext[:2]), min(ext[:2])
        if m.truth["category"] == "tower":
            assert ext[2] > plan_long, m.name
        elif m.truth["category"] == "hall":
            assert plan_long > 1.3 * plan_short and ext[2] < plan_long, m.name


# ------------------------------------------------------------------------ style markers


def _cusp_frame(p, scale):
    """A thin flat part whose single top point is a cusp: everything lies below two lines
    falling from it at 27 degrees or more (a pointed arch; a round arch, a flat top or a
    15-25 degree pediment is not)."""
    ext = np.ptp(p, axis=0)
    along = int(np.argmax(ext[:2]))
    if ext[1 - along] > 0.25 * ext[along] or ext[2] < 0.3 * ext[along]:
        return False
    eps = 1e-5 * scale
    top = p[:, 2] >= p[:, 2].max() - eps
    u_top = p[top, along]
    if np.ptp(u_top) > eps:
        return False
    drop = p[:, 2].max() - p[:, 2]
    return bool(np.all(drop >= math.tan(math.radians(27)) * np.abs(p[:, along] - u_top[0]) - eps))


def test_gothic_pointed_arches_only_in_gothic(shapes):
    for m in shapes:
        found = any(_cusp_frame(p, m.truth["scale"]) for p in _style_parts(m))
        assert found == (m.truth["style"] == "gothic"), m.name


def _round_shaft(p, scale):
    """A tall part with at least two rings of 8+ points at one radius about a vertical axis
    (a pole on the axis may share a ring's height)."""
    ext = np.ptp(p, axis=0)
    if ext[2] < 4 * ext[:2].max() or abs(ext[0] - ext[1]) > 0.05 * ext[:2].max():
        return False
    level = np.round(p[:, 2] / (1e-6 * scale))
    rings = 0
    for z in np.unique(level):
        ring = p[level == z, :2]
        r = np.linalg.norm(ring - ring.mean(axis=0), axis=1)    # a regular polygon's centre
        r = r[r > 1e-3 * ext[:2].max()]
        rings += bool(len(r) >= 8 and r.std() < 1e-3 * r.mean())
    return rings >= 2


def test_classical_columns_have_round_shafts(shapes):
    for m in _of(shapes, "classical"):
        assert any(_round_shaft(p, m.truth["scale"]) for p in _style_parts(m)), m.name


def test_pagoda_eaves_turn_up_and_roofs_sag(shapes):
    for m in _of(shapes, "pagoda"):
        parts = _style_parts(m)
        roof = max(parts, key=lambda p: np.prod(np.ptp(p[:, :2], axis=0)))
        lo, hi = roof.min(axis=0), roof.max(axis=0)
        centre, height = (lo + hi) / 2, hi[2] - lo[2]
        tol = 1e-5 * m.truth["scale"]
        at_x = (np.abs(roof[:, 0] - lo[0]) < tol) | (np.abs(roof[:, 0] - hi[0]) < tol)
        at_y = (np.abs(roof[:, 1] - lo[1]) < tol) | (np.abs(roof[:, 1] - hi[1]) < tol)
        mid = ((at_y & (np.abs(roof[:, 0] - centre[0]) < tol))
               | (at_x & (np.abs(roof[:, 1] - centre[1]) < tol)))
        assert (at_x & at_y).any() and mid.any(), m.name
        assert roof[at_x & at_y, 2].max() > roof[mid, 2].max() + 0.03 * height, m.name
        # concave: on the section through the middle of the front, the upper surface stays
        # below the straight line from the eave to the top, and sags clearly somewhere
        section = roof[(np.abs(roof[:, 0] - centre[0]) < tol) & (roof[:, 1] <= centre[1] + tol)]
        eave = section[(np.abs(section[:, 1] - lo[1]) < tol)][:, 2].max()
        peak = section[np.argmax(section[:, 2])]
        between = section[(section[:, 1] > lo[1] + tol) & (section[:, 1] < peak[1] - tol)
                          & (section[:, 2] > eave + tol)]        # the upper surface only
        line = eave + (peak[2] - eave) * (between[:, 1] - lo[1]) / (peak[1] - lo[1])
        assert np.all(between[:, 2] <= line + tol), m.name
        assert np.any(between[:, 2] < line - 0.02 * height), m.name


def test_modernist_flat_roof_and_ribbon_windows(shapes):
    for m in _of(shapes, "modernist"):
        scale = m.truth["scale"]
        v = m.vertices.astype(np.float64)
        plain = m.faces[~m.truth["face_mask"]]
        tri = v[plain]
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area = np.linalg.norm(normal, axis=1) / 2
        z_top = tri[:, :, 2].max()
        flat_top = ((normal[:, 2] > 0.999 * 2 * area)
                    & (tri[:, :, 2].min(axis=1) > z_top - 1e-5 * scale))
        footprint = np.prod(np.ptp(tri.reshape(-1, 3)[:, :2], axis=0))
        assert area[flat_top].sum() > 0.3 * footprint, m.name
        # a sill running along most of a facade, with mullions standing on it
        parts = _style_parts(m)
        extent = np.ptp(v, axis=0)
        ribbon = False
        for sill in parts:
            ext = np.ptp(sill, axis=0)
            along = int(np.argmax(ext[:2]))
            length = ext[along]
            if length < 0.45 * extent[along] or max(ext[1 - along], ext[2]) > 0.08 * length:
                continue
            lo, hi = sill.min(axis=0), sill.max(axis=0)
            mullions = 0
            for p in parts:
                e, c = np.ptp(p, axis=0), (p.min(axis=0) + p.max(axis=0)) / 2
                mullions += bool(e[:2].max() < 0.05 * length and e[2] > 2 * e[:2].max()
                                 and abs(p[:, 2].min() - hi[2]) < 1e-5 * scale
                                 and lo[along] <= c[along] <= hi[along]
                                 and abs(c[1 - along] - (lo[1 - along] + hi[1 - along]) / 2)
                                 < 0.1 * length)
            ribbon |= mullions >= 4
        assert ribbon, m.name
