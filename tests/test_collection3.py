"""collection3: the held-out curvy vs straight furniture generator keeps to its spec."""
import math
import re
from collections import Counter

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from style_coanalysis.evaluation import collection3 as c3
from style_coanalysis.meshes import face_areas, validate


@pytest.fixture(scope="module")
def coll():
    return c3.generate(25, seed=0)


def _components(mesh):
    """Connected-component label per vertex (each generated part is one welded solid)."""
    f = mesh.faces
    n = len(mesh.vertices)
    rows = np.concatenate([f[:, 0], f[:, 1], f[:, 2]])
    cols = np.concatenate([f[:, 1], f[:, 2], f[:, 0]])
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def _floor_parts(mesh):
    """Labels of the parts that touch the floor (the legs), and the vertex labels."""
    lab = _components(mesh)
    on_floor = mesh.vertices[:, 2] <= 1e-6 * mesh.truth["scale"]
    return np.unique(lab[on_floor]), lab


def _leg_bend(points):
    """Largest distance of the leg's slice centres from their best straight line, per leg width."""
    z = points[:, 2]
    top = z.max()
    keep = (z > 0.05 * top) & (z < 0.95 * top)
    zs, inv = np.unique(z[keep], return_inverse=True)
    xy = points[keep, :2]
    counts = np.bincount(inv)
    centre = np.stack([np.bincount(inv, xy[:, k]) / counts for k in range(2)], axis=1)
    radius = np.zeros(len(zs))
    np.maximum.at(radius, inv, np.linalg.norm(xy - centre[inv], axis=1))
    A = np.column_stack([zs, np.ones_like(zs)])
    coef, *_ = np.linalg.lstsq(A, centre, rcond=None)
    residual = np.linalg.norm(centre - A @ coef, axis=1).max()
    return residual / np.median(radius)


def _same(a, b):
    return (a.name == b.name and a.vertices.tobytes() == b.vertices.tobytes()
            and a.faces.tobytes() == b.faces.tobytes()
            and a.truth["style"] == b.truth["style"] and a.truth["category"] == b.truth["category"]
            and a.truth["scale"] == b.truth["scale"] and a.truth["yaw_deg"] == b.truth["yaw_deg"]
            and np.array_equal(a.truth["face_mask"], b.truth["face_mask"]))


def test_deterministic_for_a_seed_and_different_across_seeds():
    a, b = c3.generate(4, seed=11), c3.generate(4, seed=11)
    assert len(a) == 4 and all(_same(x, y) for x, y in zip(a, b))
    c = c3.generate(4, seed=12)
    assert not any(x.vertices.shape == y.vertices.shape and np.array_equal(x.vertices, y.vertices)
                   for x in a for y in c)


def test_round_robin_balance_over_the_full_grid(coll):
    counts = Counter((m.truth["style"], m.truth["category"]) for m in coll)
    assert set(counts) == {(s, c) for s in c3.STYLES for c in c3.CATEGORIES}
    assert set(counts.values()) <= {4, 5} and sum(counts.values()) == 25


def test_subsets_are_honoured():
    ms = c3.generate(5, seed=3, styles=["curvy"], categories=["chair", "bench"])
    counts = Counter((m.truth["style"], m.truth["category"]) for m in ms)
    assert set(counts) == {("curvy", "chair"), ("curvy", "bench")}
    assert sorted(counts.values()) == [2, 3]


def test_unknown_names_raise():
    with pytest.raises(ValueError):
        c3.generate(2, styles=["baroque"])
    with pytest.raises(ValueError):
        c3.generate(2, categories=["sofa"])
    with pytest.raises(ValueError):
        c3.make_shape("curvy", "sofa", np.random.default_rng(0), "x")


def test_meshes_are_valid_dense_and_standing_on_z0(coll):
    for m in coll:
        validate(m)
        assert m.vertices.dtype == np.float32 and m.faces.dtype == np.int32
        assert m.source == "collection3"
        assert 9000 <= len(m.faces) <= 77000, (m.name, len(m.faces))
        f = m.faces
        assert np.all((f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2]))
        assert face_areas(m.vertices, f).min() > 1e-12 * m.truth["scale"] ** 2
        ext = np.ptp(m.vertices.astype(np.float64), axis=0)
        assert abs(float(m.vertices[:, 2].min())) <= 1e-6 * ext.max()
        # z is up: a piece-of-furniture height, and it stands on at least four legs
        assert 0.2 * ext[:2].max() < ext[2] < 3.0 * ext[:2].max(), (m.name, ext)
        legs, _ = _floor_parts(m)
        assert len(legs) >= 4, m.name


def test_parts_are_closed_and_wound_outwards(coll):
    for m in coll[:8]:
        lab = _components(m)
        v = m.vertices.astype(np.float64)
        f = m.faces
        flab = lab[f[:, 0]]
        centre = np.stack([np.bincount(lab, v[:, k]) / np.bincount(lab) for k in range(3)], 1)
        p0, p1, p2 = (v[f[:, k]] - centre[flab] for k in range(3))
        vol = np.bincount(flab, np.einsum("ij,ij->i", p0, np.cross(p1, p2)) / 6)
        assert np.all(vol > 0), m.name
        # closed: every undirected edge is used by exactly two faces
        e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
        _, uses = np.unique(e, axis=0, return_counts=True)
        assert np.all(uses == 2), m.name


def test_sizes_span_the_scale_range(coll):
    lo, hi = c3.SCALE_RANGE
    diag = np.array([np.linalg.norm(np.ptp(m.vertices.astype(np.float64), axis=0)) for m in coll])
    assert diag.min() >= lo and diag.max() <= hi * math.sqrt(3)
    assert diag.max() / diag.min() > 100
    for m in coll:  # truth scale is the largest dimension before the yaw
        a = math.radians(m.truth["yaw_deg"])
        c, s = math.cos(a), math.sin(a)
        v = m.vertices.astype(np.float64) @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        assert np.ptp(v, axis=0).max() == pytest.approx(m.truth["scale"], rel=1e-4)
        assert 0.0 <= m.truth["yaw_deg"] < 360.0


def test_triangle_counts_do_not_depend_on_style(coll):
    logs = {s: [math.log(len(m.faces)) for m in coll if m.truth["style"] == s] for s in c3.STYLES}
    span = math.log(77000 / 9000)
    assert abs(np.mean(logs["curvy"]) - np.mean(logs["straight"])) < 0.12 * span
    for s in c3.STYLES:  # each style covers the range
        assert max(logs[s]) - min(logs[s]) > 0.6 * span


def test_face_mask_marks_some_but_not_all_faces(coll):
    for m in coll:
        mask = m.truth["face_mask"]
        assert mask.dtype == bool and mask.shape == (len(m.faces),)
        assert mask.any() and not mask.all(), m.name


def test_curvy_legs_bend_and_straight_legs_do_not(coll):
    for m in coll:
        legs, lab = _floor_parts(m)
        v = m.vertices.astype(np.float64)
        bends = [_leg_bend(v[lab == leg]) for leg in legs]
        if m.truth["style"] == "curvy":
            assert min(bends) > 0.1, (m.name, bends)
        else:
            assert max(bends) < 1e-3, (m.name, bends)
        # the legs are style-carrying faces
        leg_faces = np.isin(lab[m.faces[:, 0]], legs)
        assert m.truth["face_mask"][leg_faces].all(), m.name


def test_proportions_come_from_a_style_free_stream():
    curvy = c3.make_shape("curvy", "table", np.random.default_rng(5), "a", n_triangles=9000)
    straight = c3.make_shape("straight", "table", np.random.default_rng(5), "b", n_triangles=9000)
    assert curvy.truth["scale"] == straight.truth["scale"]
    assert curvy.truth["yaw_deg"] == straight.truth["yaw_deg"]
    e1 = np.ptp(curvy.vertices.astype(np.float64), axis=0)
    e2 = np.ptp(straight.vertices.astype(np.float64), axis=0)
    assert np.allclose(e1, e2, rtol=0.15), (e1, e2)


def test_names_say_nothing_about_labels(coll):
    names = [m.name for m in coll]
    assert len(set(names)) == 25 and all(re.fullmatch(r"c3_\d{3}", n) for n in names)
    assert sorted(names) == [f"c3_{i:03d}" for i in range(25)]
    for n in names:
        assert not any(w in n for w in c3.STYLES + c3.CATEGORIES)
    # the order of names is not the order of labels
    styles = [m.truth["style"] for m in coll]
    assert styles != sorted(styles)
