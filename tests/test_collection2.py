"""The second generated collection (style_coanalysis.evaluation.collection2): labels, geometry
sanity, determinism and the properties that keep labels from leaking through names, sizes,
orientation or triangle counts. Pure numpy; no Blender."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from style_coanalysis.evaluation import collection2 as C
from style_coanalysis.meshes import Mesh, face_areas, validate

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def shapes40():
    return C.generate(40, seed=3)


@pytest.fixture(scope="module")
def shapes120():
    return C.generate(120, seed=0)


def test_api_names():
    assert C.STYLES == ("barleytwist", "shellcarved", "spindle", "spadefoot")
    assert C.CATEGORIES == ("desk", "bench", "armchair", "bookcase", "sidetable")
    m = C.make_shape("spindle", "desk", np.random.default_rng(1), "c2_x")
    assert isinstance(m, Mesh) and m.name == "c2_x"
    assert m.truth["style"] == "spindle" and m.truth["category"] == "desk"


def test_deterministic():
    a = C.generate(10, seed=7)
    b = C.generate(10, seed=7)
    for x, y in zip(a, b):
        assert x.name == y.name
        assert np.array_equal(x.vertices, y.vertices)
        assert np.array_equal(x.faces, y.faces)
        assert np.array_equal(x.truth["face_mask"], y.truth["face_mask"])
        assert x.truth["style"] == y.truth["style"] and x.truth["category"] == y.truth["category"]
    c = C.generate(10, seed=8)
    assert any(not np.array_equal(x.vertices, y.vertices) or x.vertices.shape != y.vertices.shape
               for x, y in zip(a, c))


def test_the_same_shapes_on_every_processor():
    """numpy picks some kernels by processor (an AVX-512 argsort that orders equal keys
    otherwise, an AVX-512 pow that rounds otherwise): the same seed must give the same shapes on
    every machine. Here generated once as this processor runs numpy and once with its AVX-512
    kernels switched off (on a machine without AVX-512 both runs are the same run)."""
    from numpy.core._multiarray_umath import __cpu_features__
    script = ("import hashlib; from style_coanalysis.evaluation.collection2 import generate; "
              "print([hashlib.sha1(m.vertices.tobytes() + m.faces.tobytes()).hexdigest() "
              "for m in generate(5, seed=0)])")
    avx512 = " ".join(k for k, on in __cpu_features__.items() if on and k.startswith("AVX512"))

    def run(**env):
        return subprocess.run([sys.executable, "-c", script], env={**os.environ, **env},
                              cwd=ROOT, capture_output=True, text=True, check=True).stdout

    assert run() == run(NPY_DISABLE_CPU_FEATURES=avx512)


def test_every_cell_present_and_even(shapes40):
    assert len(shapes40) == 40
    cells = {}
    for m in shapes40:
        key = (m.truth["style"], m.truth["category"])
        cells[key] = cells.get(key, 0) + 1
    assert set(cells) == {(s, c) for s in C.STYLES for c in C.CATEGORIES}
    assert set(cells.values()) == {2}


def test_round_robin_uneven_size():
    ms = C.generate(23, seed=1, styles=["spindle", "spadefoot"], categories=["desk", "bench", "bookcase"])
    counts = {}
    for m in ms:
        k = (m.truth["style"], m.truth["category"])
        counts[k] = counts.get(k, 0) + 1
    assert len(counts) == 6 and max(counts.values()) - min(counts.values()) <= 1


def test_geometry_and_masks(shapes40):
    for m in shapes40:
        validate(m)
        v, f = m.vertices, m.faces
        assert v.dtype == np.float32 and f.dtype == np.int32 and f.shape[1] == 3
        assert np.all(np.isfinite(v))
        assert f.min() >= 0 and f.max() < len(v)
        mask = m.truth["face_mask"]
        assert mask.dtype == bool and mask.shape == (len(f),)
        assert mask.any() and not mask.all()
        area = face_areas(v, f)
        assert np.all(area > 0), m.name
        share = area[mask].sum() / area.sum()
        assert 0.05 <= share <= 0.70, (m.name, m.truth["style"], m.truth["category"], share)
        extent = float(np.ptp(v, axis=0).max())
        assert abs(float(v[:, 2].min())) <= 1e-6 * extent
        assert 2900 <= len(f) <= 12000


def test_outward_winding(shapes40):
    # closed parts wound outward give a positive enclosed volume overall
    for m in shapes40[:12]:
        v = m.vertices.astype(np.float64)
        v = v - v.mean(0)
        a, b, c = v[m.faces[:, 0]], v[m.faces[:, 1]], v[m.faces[:, 2]]
        assert np.einsum("ij,ij->i", a, np.cross(b, c)).sum() > 0, m.name


def test_names_do_not_leak(shapes40):
    names = [m.name for m in shapes40]
    assert len(set(names)) == len(names)
    assert sorted(names) == [f"c2_{i:03d}" for i in range(40)]
    words = [w.lower() for w in C.STYLES + C.CATEGORIES] + ["barley", "shell", "spade", "twist"]
    for n in names:
        assert not any(w in n.lower() for w in words)
        assert not any(w in m.source.lower() for w in words for m in shapes40)
    # name order is shuffled with respect to the labels
    by_name = sorted(shapes40, key=lambda m: m.name)
    styles = [m.truth["style"] for m in by_name]
    assert styles != sorted(styles)


def test_scale_and_yaw_randomised(shapes120):
    scales = np.array([m.truth["scale"] for m in shapes120])
    yaws = np.array([m.truth["yaw_deg"] for m in shapes120])
    assert scales.min() >= 0.3 and scales.max() <= 300
    assert scales.max() / scales.min() > 50
    assert yaws.min() >= 0 and yaws.max() < 360 and np.ptp(yaws) > 180
    # the size of the object in file units follows the unit scale, not the style
    for st in C.STYLES:
        s = scales[[m.truth["style"] == st for m in shapes120]]
        assert s.max() / s.min() > 5


def test_triangle_counts_do_not_betray_style(shapes120):
    counts = {st: [] for st in C.STYLES}
    for m in shapes120:
        counts[m.truth["style"]].append(len(m.faces))
    means = np.array([np.mean(v) for v in counts.values()])
    assert means.max() / means.min() < 1.15, dict(zip(counts, means))
    allc = np.array([len(m.faces) for m in shapes120])
    assert allc.min() >= 2900 and np.ptp(allc) > 4000


def test_subsets_and_bad_names():
    ms = C.generate(6, seed=2, styles=["barleytwist"], categories=("bench", "desk"))
    assert {m.truth["style"] for m in ms} == {"barleytwist"}
    assert {m.truth["category"] for m in ms} == {"bench", "desk"}
    ms = C.generate(4, seed=2, styles="spadefoot")
    assert {m.truth["style"] for m in ms} == {"spadefoot"}
    with pytest.raises(ValueError):
        C.generate(4, styles=["rococo"])
    with pytest.raises(ValueError):
        C.generate(4, categories=["chair"])
    with pytest.raises(ValueError):
        C.make_shape("spindle", "sofa", np.random.default_rng(0), "x")
    assert C.generate(0) == []
