"""The sample collection: deterministic, balanced, valid, and style not guessable from global shape."""
import numpy as np
import pytest

from style_coanalysis import metrics, sample
from style_coanalysis.evaluation import baselines
from style_coanalysis.meshes import face_areas, validate


@pytest.fixture(scope="module")
def shapes():
    return sample.generate(120, seed=0)


def test_same_seed_same_arrays_other_seed_differs():
    a, b, c = sample.generate(20, seed=4), sample.generate(20, seed=4), sample.generate(20, seed=5)
    for x, y in zip(a, b):
        assert x.name == y.name
        assert np.array_equal(x.vertices, y.vertices) and np.array_equal(x.faces, y.faces)
        assert np.array_equal(x.truth["face_mask"], y.truth["face_mask"])
    assert any(len(x.vertices) != len(z.vertices) or not np.array_equal(x.vertices, z.vertices)
               for x, z in zip(a, c))


def test_balanced_every_style_in_every_category(shapes):
    assert len(shapes) >= 120
    styles = [m.truth["style"] for m in shapes]
    cats = [m.truth["category"] for m in shapes]
    assert len(set(styles)) >= 4 and len(set(cats)) >= 4
    pairs = {(s, c) for s, c in zip(styles, cats)}
    assert pairs == {(s, c) for s in set(styles) for c in set(cats)}
    _, counts = np.unique(styles, return_counts=True)
    assert counts.max() - counts.min() <= 1
    assert len({m.name for m in shapes}) == len(shapes)


def test_meshes_valid_grounded_moderate_with_partial_masks(shapes):
    for m in shapes:
        validate(m)
        assert abs(float(m.vertices[:, 2].min())) < 1e-6, m.name          # stands on z = 0
        assert 1000 <= len(m.faces) <= 10000, (m.name, len(m.faces))
        areas = face_areas(m.vertices, m.faces)                          # renderers warn on these
        assert areas.min() > 1e-9 * np.ptp(m.vertices, axis=0).max() ** 2, m.name
        mask = m.truth["face_mask"]
        assert mask.dtype == bool and mask.shape == (len(m.faces),)
        assert 0 < mask.sum() < len(mask), m.name


def test_within_style_variation(shapes):
    """Shapes of one style and category differ in size and structure, not just position."""
    for style in sample.STYLES:
        group = [m for m in shapes if m.truth["style"] == style and m.truth["category"] == "chair"]
        heights = [np.ptp(m.vertices[:, 2]) for m in group]
        assert np.ptp(heights) > 0.05, style


def test_global_shape_baseline_near_chance(shapes):
    feats = baselines.global_shape_features(shapes)
    truth = np.array([m.truth["style"] for m in shapes])
    k = len(set(truth))
    pur = np.mean([metrics.purity(baselines.cluster_baseline(feats, k, seed), truth)
                   for seed in range(3)])
    assert pur <= 1.0 / k + 0.15, pur


def test_purity_eq5_and_triplets_on_small_cases():
    truth = np.array(["a", "a", "a", "b", "b", "c"])
    assert metrics.purity([0, 0, 1, 1, 1, 2], truth) == pytest.approx(5 / 6)
    assert metrics.purity(np.arange(6), truth) == 1.0          # singletons are trivially pure
    assert metrics.purity(np.zeros(6), truth) == pytest.approx(0.5)
    s = metrics.score([0, 0, 0, 1, 1, 2], truth)
    assert s["purity"] == s["nmi"] == s["ari"] == pytest.approx(1.0)
    D = np.array([[0, 1, 2], [1, 0, 3], [2, 3, 0]], float)
    assert metrics.triplet_accuracy(D, [[0, 1, 2], [0, 2, 1], [1, 0, 2]]) == pytest.approx(2 / 3)


def test_line_statistics_see_orientation_and_ink():
    img = np.zeros((40, 40), np.float32)
    img[::8, :] = 1.0                                            # horizontal lines
    stats = baselines.line_statistics([np.stack([img, img]), np.stack([img.T, img.T])])
    assert stats.shape == (2, 1 + baselines.N_ORIENTATIONS)
    assert stats[0, 0] == pytest.approx(img.mean())
    assert np.argmax(stats[0, 1:]) != np.argmax(stats[1, 1:])  # rotated drawing, other bin
    assert np.allclose(stats[:, 1:].sum(1), 1.0)
