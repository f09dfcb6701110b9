"""Style distance and its stored space (pure: no Blender)."""
import numpy as np
import pytest

from style_coanalysis.clustering import style_distance
from style_coanalysis.meshes import InputError
from style_coanalysis.similarity import (SPACE_FILE, StyleMetric, StyleSpace, _pair_terms,
                                         label_triplets)


def make_space(x, clusters=None, given=None, labels=None, weights=None):
    n = len(x)
    return StyleSpace([f"s{i:02d}" for i in range(n)], x,
                      np.zeros(n, int) if clusters is None else clusters, np.full(n, 0.5),
                      np.zeros(n, bool) if given is None else given,
                      [""] * n if labels is None else labels, weights)


def style_data(rng, n=60, noise=3.0):
    """Style in coordinate 0 (two groups), larger nuisance variation in coordinates 1..4."""
    style = np.arange(n) % 2
    x = np.column_stack([np.where(style, 1.0, -1.0) + 0.1 * rng.standard_normal(n),
                         noise * rng.standard_normal((n, 4))]) + 5.0
    return x, style


def triplets_of(style, rng, count):
    out = []
    while len(out) < count:
        a, b, c = rng.integers(len(style), size=3)
        if a != b and style[a] == style[b] != style[c]:
            out.append((a, b, c))
    return np.array(out)


def test_unsupervised_ranking_is_the_cosine_style_distance():
    x = np.random.default_rng(0).standard_normal((12, 5))
    space = make_space(x)
    D = style_distance(x)
    for i in range(12):
        want = [j for j in np.argsort(D[i], kind="stable") if j != i]
        got = [space.index(n) for n, _ in space.ranking(space.names[i])]
        assert got == want


def test_metric_learned_from_triplets_finds_the_style_coordinate():
    rng = np.random.default_rng(1)
    x, style = style_data(rng)
    train, test = triplets_of(style, rng, 100), triplets_of(style, rng, 500)
    plain = make_space(x)
    metric = StyleMetric().fit(x, train, np.zeros(len(x), int))
    learned = make_space(x, weights=metric.weights_)
    assert learned.triplet_accuracy(test) > plain.triplet_accuracy(test)
    assert metric.weights_[0] > metric.weights_[1:5].max()
    assert (metric.weights_ >= 0).all()


def test_too_few_triplets_keep_the_unsupervised_metric():
    rng = np.random.default_rng(2)
    x, style = style_data(rng)
    metric = StyleMetric().fit(x, triplets_of(style, rng, 3), np.zeros(len(x), int))
    assert np.array_equal(metric.weights_, StyleMetric.prior(x.shape[1]))


def test_cluster_term_separates_clusters():
    x = np.ones((4, 3))
    space = make_space(x, clusters=np.array([0, 0, 1, 1]), weights=[0, 0, 0, 1.0])
    assert space.triplet_accuracy([("s00", "s01", "s02")]) == 1.0
    assert space.triplet_accuracy([("s00", "s02", "s01")]) == 0.0
    assert make_space(x).triplet_accuracy([(0, 1, 2)]) == 0.5       # a tie counts half
    assert _pair_terms(x, np.array([0, 0, 1, 1]), np.array([0]), np.array([3]))[0, -1] == 1


def test_label_triplets_follow_the_labels():
    given = np.array([True] * 6 + [False] * 4)
    labels = ["a", "a", "b", "b", "c", "c", "a", "b", "c", "a"]
    t = label_triplets(given, labels, np.random.default_rng(0), limit=50)
    assert len(t) > 0 and len(np.unique(t, axis=0)) == len(t)
    for a, b, c in t:
        assert given[[a, b, c]].all()
        assert labels[a] == labels[b] != labels[c]
    assert len(label_triplets(np.array([True, False]), ["a", "b"], np.random.default_rng(0))) == 0


def test_save_and_load(tmp_path):
    rng = np.random.default_rng(3)
    space = make_space(rng.standard_normal((5, 3)), clusters=np.array([0, 1, 0, 1, 1]),
                       given=np.array([1, 0, 0, 1, 0], bool), labels=["x", "y", "x", "y", "y"],
                       weights=[1, 2, 3, 4])
    space.save(tmp_path / SPACE_FILE)
    assert [p.name for p in tmp_path.iterdir()] == [SPACE_FILE]       # no temporary file left
    back = StyleSpace.load(tmp_path)
    assert back.names == space.names and back.labels == space.labels
    for k in ("features", "clusters", "label_given", "weights"):
        assert np.array_equal(getattr(back, k), getattr(space, k))
    assert back.ranking("s00") == space.ranking("s00")


def test_load_refuses_what_is_not_a_result(tmp_path):
    with pytest.raises(InputError, match="not a folder"):
        StyleSpace.load(tmp_path / "missing")
    with pytest.raises(InputError, match=f"holds no {SPACE_FILE}"):
        StyleSpace.load(tmp_path)
    (tmp_path / SPACE_FILE).write_text("not numpy")
    with pytest.raises(InputError, match="not a readable style space"):
        StyleSpace.load(tmp_path)
    with pytest.raises(InputError, match="'nope' is not among the analysed shapes"):
        make_space(np.eye(3)).ranking("nope")
