"""The paper's method (style_coanalysis.paper_method) end to end on procedural drawings."""
import numpy as np
import pytest
from synthetic import STYLES, make_collection, purity

from style_coanalysis.paper_method import build_filter_bank
from style_coanalysis.features import hog_images, patch_blocks
from style_coanalysis.meshes import InputError
from style_coanalysis.paper_method import (N_SEEDS, PATCH_SIZE, analyse_paper, eq4_reselect,
                                           seed_support, _word_clusters)
from style_coanalysis.params import AnalysisParams
from style_coanalysis.patches import extract_patches
from style_coanalysis.pipeline import AnalysisResult
from style_coanalysis.progress import Cancelled

N_REPS = 20
PARAMS = AnalysisParams(method="paper", n_representatives=N_REPS, n_clusters=3, max_rounds=3,
                        random_state=0)


@pytest.fixture(scope="module")
def collection():
    return make_collection(n_per_cell=3, n_views=4, seed=0)      # 27 shapes, 4 views


@pytest.fixture(scope="module")
def maps(collection):
    return np.stack([hog_images(d.images) for d in collection[0]])


@pytest.fixture(scope="module")
def unsupervised(collection, maps):
    stages = []
    result = analyse_paper(collection[0], PARAMS, maps=maps,
                           progress=lambda st, d, t: stages.append(st))
    return result, stages


def _chance(clusters, truth, n=200):
    rng = np.random.default_rng(0)
    return np.mean([purity(rng.permutation(clusters), truth) for _ in range(n)])


def test_eq4_as_printed():
    # 4 shapes in 2 clusters, 3 patches: omega = 1/2 - 1/3 = 1/6 inside, -1/3 outside
    x = np.array([[1, 1, 1], [1, 1, 0], [0, 1, 1], [0, 1, 0]], bool)
    clusters = np.array([0, 0, 1, 1])
    sel = eq4_reselect(x, clusters, n_patches=3, mu=0.2)
    np.testing.assert_allclose(sel.signed, [[1.0, -1 / 3, 0.0], [-1.0, -1 / 3, 0.0]])
    assert sel.threshold == pytest.approx(0.2 * 3 / 2)
    np.testing.assert_array_equal(sel.keep, [True, True, False])   # |delta| > 0.3
    sel = eq4_reselect(x, clusters, n_patches=3, mu=0.5)           # threshold 0.75
    np.testing.assert_array_equal(sel.keep, [True, False, False])
    cluster, score = _word_clusters(sel, sel.keep)
    # patch 0 is frequent in cluster 0 (and absent from 1): it marks cluster 0
    assert cluster.tolist() == [0] and score.tolist() == [pytest.approx(1.0)]


def test_support_is_seed_patch_membership(collection, maps):
    drawings = collection[0]
    patches = extract_patches(drawings, size=PATCH_SIZE)
    patches = patches.subset(patches.seed < N_SEEDS)
    bank = build_filter_bank(maps, patches.shape, patches.view, patches.seed, patches.centre,
                             PATCH_SIZE, N_REPS, 0)
    x = seed_support(maps, patches, bank, len(drawings))
    assert x.shape == (len(drawings), len(bank))
    # a representative is a real patch, so at least its own shape has a member of its cluster
    assert x[bank.shape, np.arange(len(bank))].all()
    # and support is neither everything nor nothing
    assert 0.05 < x.mean() < 0.95


def test_unsupervised_with_k_given(collection, unsupervised):
    drawings, styles, cats = collection
    result, stages = unsupervised
    n = len(drawings)
    assert isinstance(result, AnalysisResult)
    assert result.clusters.shape == (n,) and result.n_clusters == 3
    assert set(result.clusters.tolist()) == {0, 1, 2}
    # the clusters follow the drawings (style or the category distractor), not chance
    best = max(purity(result.clusters, styles), purity(result.clusters, cats))
    assert best > _chance(result.clusters, styles) + 0.1
    # round 0 encodes with all 4 x 20 per-view representatives; eq. 4 then selects a subset
    assert result.rounds[0]["n_filters"] == 4 * N_REPS
    assert 0 < result.rounds[0]["n_selected"] < 4 * N_REPS
    f = len(result.style_filters)
    nb = patch_blocks(48)
    assert result.words.shape == (f, nb, nb, 36)
    assert result.word_cluster.shape == result.word_score.shape == (f,)
    assert set(result.word_cluster.tolist()) <= {-1, 0, 1, 2} and (result.word_cluster >= 0).any()
    for k, sf in enumerate(result.style_filters):
        assert sf.cluster == result.word_cluster[k] and np.array_equal(sf.hog, result.words[k])
    w = result.view_weights
    assert w.shape == (4,) and np.all(w >= 0) and w.sum() == pytest.approx(1.0)
    assert result.fused.shape[0] == n and np.all(result.fused >= 0)
    assert np.all((result.confidence >= 0) & (result.confidence <= 1))
    assert result.classes is None and result.predicted is None and not result.label_given.any()
    assert 1 <= len(result.rounds) <= PARAMS.max_rounds
    for stage in ("patches", "representatives", "encode", "fuse", "cluster", "reselect"):
        assert stage in stages and stage in result.timings


def test_unsupervised_chooses_k_by_rotation_cost(collection, maps):
    result = analyse_paper(collection[0], AnalysisParams(method="paper", n_representatives=N_REPS,
                                                         n_clusters=None, max_rounds=2), maps=maps)
    last = result.rounds[-1]
    costs = last["rotation_costs"]
    assert set(costs) == set(range(2, 11))
    best = min(costs.values())      # the self-tuning rule: largest k within 1e-3 of the best cost
    k = max(c for c, v in costs.items() if v - best <= 1e-3)
    assert result.n_clusters == last["n_clusters"] == len(np.unique(result.clusters)) == k


def test_labels_are_respected(collection, maps):
    drawings, styles, _ = collection
    rng = np.random.default_rng(1)
    idx = rng.choice(len(drawings), 7, replace=False)
    # give some labels that contradict the drawings' styles: they must still be kept
    labels = {drawings[i].name: STYLES[(styles[i] + (1 if j < 2 else 0)) % 3]
              for j, i in enumerate(idx)}
    result = analyse_paper(drawings, PARAMS, labels=labels, maps=maps)
    assert result.classes == sorted(STYLES) and result.n_clusters == 3
    assert all(result.predicted[i] == labels[d.name]
               for i, d in enumerate(drawings) if d.name in labels)
    assert result.label_given.sum() == len(labels)
    assert all(result.classes[c] == p for c, p in zip(result.clusters, result.predicted))
    assert np.all(result.confidence[result.label_given] == 1.0)
    assert result.confidence[~result.label_given].mean() < 1.0     # predicted, with doubt


def test_triplets_are_honoured(collection, maps, unsupervised):
    drawings, styles, _ = collection
    rng = np.random.default_rng(2)
    trip = set()
    while len(trip) < 2 * len(drawings):
        a, b, c = rng.choice(len(drawings), 3, replace=False)
        if styles[a] == styles[b] != styles[c]:
            trip.add((drawings[a].name, drawings[b].name, drawings[c].name))
    trip = sorted(trip)
    result = analyse_paper(drawings, PARAMS, triplets=trip, maps=maps)
    index = {d.name: i for i, d in enumerate(drawings)}

    def satisfied(cl):
        return np.mean([cl[index[a]] == cl[index[b]] != cl[index[c]] for a, b, c in trip])

    assert result.n_clusters <= 3 and result.classes is None
    assert satisfied(result.clusters) > satisfied(unsupervised[0].clusters) + 0.2
    assert purity(result.clusters, styles) > purity(unsupervised[0].clusters, styles)


def test_deterministic_and_maps_optional(collection, unsupervised):
    again = analyse_paper(collection[0], PARAMS)          # maps computed inside this time
    first = unsupervised[0]
    np.testing.assert_array_equal(again.clusters, first.clusters)
    np.testing.assert_allclose(again.fused, first.fused)
    np.testing.assert_array_equal(again.words, first.words)
    assert "hog" in again.timings and "hog" not in first.timings


def test_bad_input_and_cancel(collection, maps):
    drawings = collection[0]
    with pytest.raises(InputError, match="only"):
        analyse_paper(drawings[:2], PARAMS)
    with pytest.raises(InputError, match="either"):
        a, b, c = (d.name for d in drawings[:3])
        analyse_paper(drawings, PARAMS, labels={a: "x", b: "y"}, triplets=[(a, b, c)])
    calls = []
    with pytest.raises(Cancelled):
        analyse_paper(drawings, PARAMS, maps=maps, progress=lambda *a: calls.append(a),
                      cancel=lambda: len(calls) > 2)
    assert len(calls) == 3
