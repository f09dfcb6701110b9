"""The whole analysis on procedural drawings whose style is known (and never shown to it)."""
from dataclasses import replace

import numpy as np
import pytest
from synthetic import STYLES, make_collection, purity

from style_coanalysis.features import patch_blocks
from style_coanalysis.meshes import InputError
from style_coanalysis.params import AnalysisParams
from style_coanalysis.pipeline import LABEL_FOLDS, AnalysisResult, analyse, style_similarity
from style_coanalysis.progress import Cancelled

PARAMS = AnalysisParams(n_representatives=20, n_clusters=3, max_rounds=3, random_state=0)


@pytest.fixture(scope="module")
def collection():
    return make_collection(n_per_cell=4, n_views=4, seed=0)


@pytest.fixture(scope="module")
def unsupervised(collection):
    drawings, _, _ = collection
    stages = []
    result = analyse(drawings, PARAMS, progress=lambda st, d, t: stages.append(st))
    return result, stages


def _labels(collection, share=0.25, seed=1):
    drawings, styles, _ = collection
    rng = np.random.default_rng(seed)
    idx = rng.choice(len(drawings), int(share * len(drawings)), replace=False)
    return {drawings[i].name: STYLES[styles[i]] for i in idx}


def _triplets(collection, n, seed=2):
    drawings, styles, _ = collection
    rng = np.random.default_rng(seed)
    out = set()
    while len(out) < n:
        a, b, c = rng.choice(len(drawings), 3, replace=False)
        if styles[a] == styles[b] != styles[c]:
            out.add((drawings[a].name, drawings[b].name, drawings[c].name))
    return sorted(out)


def test_unsupervised_finds_style_above_chance(collection, unsupervised):
    drawings, styles, _ = collection
    result, stages = unsupervised
    assert isinstance(result, AnalysisResult)
    n = len(drawings)
    assert result.clusters.shape == (n,) and result.n_clusters == 3
    assert set(result.clusters) == {0, 1, 2}
    # chance: the same cluster sizes with shapes dealt at random (about 0.46 here, not 1/3)
    rng = np.random.default_rng(0)
    chance = np.mean([purity(rng.permutation(result.clusters), styles) for _ in range(200)])
    assert purity(result.clusters, styles) > chance + 0.1
    assert result.confidence.shape == (n,) and 0 <= result.confidence.min() <= result.confidence.max() <= 1
    assert result.predicted is None and not result.label_given.any()
    # the final style words: words of the first dictionary, each marking one cluster
    f = len(result.style_filters)
    assert 0 < f and np.sum(result.word_cluster >= 0) == f
    nb = patch_blocks(PARAMS.patch_size)      # comparable with localisation's patch descriptors
    assert all(0 <= sf.cluster < 3 and sf.hog.shape == (nb, nb, 36) for sf in result.style_filters)
    assert result.rounds[0]["n_filters"] > min(r["n_selected"] for r in result.rounds)  # selected
    for stage in ("hog", "representatives", "encode", "fuse", "cluster", "reselect"):
        assert stage in stages and stage in result.timings
    assert stages.count("hog") == n and stages.count("encode") == n      # shape by shape
    assert stages.count("representatives") == 2 * PARAMS.n_dictionaries  # one per vocabulary
    d = style_similarity(result)
    assert d.shape == (n, n) and np.allclose(d, d.T) and np.allclose(np.diag(d), 0, atol=1e-6)


@pytest.fixture(scope="module")
def labelled(collection):
    return analyse(collection[0], PARAMS, labels=_labels(collection))


def test_the_automatic_k_is_the_largest_spectral_gap_and_reports_every_gap(collection,
                                                                          unsupervised):
    drawings, _, _ = collection
    assert unsupervised[0].k_gaps is None                                 # k was given
    result = analyse(drawings, AnalysisParams(n_representatives=20, n_clusters=None,
                                              max_rounds=2, random_state=0))
    gaps = result.k_gaps
    assert set(gaps) == set(range(2, min(10, len(drawings) // 4) + 1))
    assert result.n_clusters == max(gaps, key=gaps.get) == len(set(result.clusters))


def test_the_dictionaries_agreement_says_how_firmly_the_drawings_hold_the_clusters(
        collection, unsupervised, labelled):
    from style_coanalysis import pipeline
    drawings, styles, _ = collection
    result = unsupervised[0]
    assert -1.0 <= result.dictionary_agreement <= 1.0
    assert labelled.dictionary_agreement is None                 # labels decided the clusters
    # it reads the clusters: the same clusters shuffled agree less with the dictionaries' cuts
    encoded = pipeline.encode(drawings, PARAMS)
    agree = pipeline._dictionary_agreement(encoded.dictionaries, encoded.lines, PARAMS,
                                           result.clusters, 3)
    assert agree == pytest.approx(result.dictionary_agreement)
    shuffled = np.random.default_rng(0).permutation(result.clusters)
    assert pipeline._dictionary_agreement(encoded.dictionaries, encoded.lines, PARAMS,
                                          shuffled, 3) < agree - 0.2
    one = AnalysisParams(n_representatives=20, n_clusters=3, max_rounds=1, n_dictionaries=1)
    assert analyse(drawings, one).dictionary_agreement is None      # nothing to compare with


def test_labels_are_kept_and_map_to_classes(collection, labelled):
    drawings, styles, _ = collection
    labels, result = _labels(collection), labelled
    assert result.classes == sorted(STYLES)
    assert all(result.predicted[i] == labels[d.name]
               for i, d in enumerate(drawings) if d.name in labels)
    assert result.label_given.sum() == len(labels)
    assert all(result.classes[c] == p for c, p in zip(result.clusters, result.predicted))
    assert np.all(result.confidence[result.label_given] == 1.0)


def test_labels_never_make_the_result_worse(collection, unsupervised, labelled):
    styles = collection[1]
    assert purity(labelled.clusters, styles) >= purity(unsupervised[0].clusters, styles)


def test_the_order_of_the_shapes_does_not_change_the_partition(collection, unsupervised):
    from sklearn.metrics import adjusted_rand_score
    drawings = collection[0]
    perm = np.random.default_rng(5).permutation(len(drawings))
    again = analyse([drawings[i] for i in perm], PARAMS).clusters
    back = np.empty_like(again)
    back[perm] = again
    assert adjusted_rand_score(unsupervised[0].clusters, back) == 1.0


@pytest.mark.parametrize("mode", ["labels", "triplets"])
def test_the_order_of_the_shapes_does_not_change_a_constrained_partition(collection, mode):
    """The constraints name shapes, so they follow them into any order; the partition too."""
    from sklearn.metrics import adjusted_rand_score
    drawings = collection[0]
    given = ({"labels": _labels(collection)} if mode == "labels"
             else {"triplets": _triplets(collection, len(drawings))})
    first = analyse(drawings, PARAMS, **given).clusters
    perm = np.random.default_rng(5).permutation(len(drawings))
    again = analyse([drawings[i] for i in perm], PARAMS, **given).clusters
    back = np.empty_like(again)
    back[perm] = again
    assert adjusted_rand_score(first, back) == 1.0


def test_triplets_steer_the_clustering(collection, unsupervised):
    """Triplets that describe the categories instead (a user's own notion of style) pull the
    partition towards the categories, away from what the drawings alone give."""
    drawings, styles, cats = collection
    result = analyse(drawings, PARAMS, triplets=_triplets((drawings, cats, None), 2 * len(drawings)))
    assert purity(result.clusters, cats) > purity(unsupervised[0].clusters, cats) + 0.2


def test_deterministic(collection, unsupervised):
    drawings, _, _ = collection
    again = analyse(drawings, PARAMS)
    np.testing.assert_array_equal(again.clusters, unsupervised[0].clusters)
    np.testing.assert_allclose(again.fused, unsupervised[0].fused)


def test_later_rounds_refine_the_all_words_graph_rather_than_replace_it(collection, monkeypatch):
    """After the first round the cut reads the mean of the first round's graph (every word) and
    the kept words' graph, so the words one round keeps cannot pull the next cut away from what
    all the words say (the damping that keeps a few redrawn pixels from growing round by round)."""
    from style_coanalysis import pipeline
    drawings, _, _ = collection
    built, cut = [], []
    style_graph, cluster = pipeline._style_graph, pipeline._cluster

    def recording_graph(*args, **kwargs):
        out = style_graph(*args, **kwargs)
        built.append(out[0].toarray())
        return out

    def recording_cut(a, *args, **kwargs):
        cut.append(a.toarray())
        return cluster(a, *args, **kwargs)

    monkeypatch.setattr(pipeline, "_style_graph", recording_graph)
    monkeypatch.setattr(pipeline, "_cluster", recording_cut)
    result = analyse(drawings, PARAMS)
    assert len(result.rounds) >= 2 and len(cut) == len(built) == len(result.rounds)
    assert result.rounds[1]["n_filters"] < len(result.words)      # round 2 read fewer words
    np.testing.assert_allclose(cut[0], built[0])
    for later, own in zip(cut[1:], built[1:]):
        assert not np.allclose(own, built[0])
        np.testing.assert_allclose(later, 0.5 * (built[0] + own))


def test_the_labels_reading_is_chosen_in_the_first_round_and_kept(collection, monkeypatch):
    """Which reading of the labels to use (the graph's own cut, the seeded cut or the label
    metric) is chosen once, as the automatic k is: a choice made again every round flipped with
    small moves of the graph, and the result with it."""
    from style_coanalysis import pipeline
    given = []
    transduction = pipeline._label_transduction

    def recording(*args, **kwargs):
        out = transduction(*args, **kwargs)
        given.append((args[5] if len(args) > 5 else kwargs.get("reading"), out[2]))
        return out

    monkeypatch.setattr(pipeline, "_label_transduction", recording)
    result = analyse(collection[0], PARAMS, labels=_labels(collection))
    assert len(result.rounds) >= 2 and len(given) == len(result.rounds)
    assert given[0][0] is None and given[0][1] in ("own", "seeded", "metric")
    assert all(asked == used == given[0][1] for asked, used in given[1:])


def test_the_cuts_run_on_one_thread_and_the_triplet_clustering_on_every_core(collection,
                                                                            monkeypatch):
    """The cuts' fits are small, and on more threads their BLAS and OpenMP pools wait on each
    other (3,000 shapes, 10% labels: twice as slow on two threads as on one); the triplet
    clustering's N x N products gain from threads."""
    from threadpoolctl import threadpool_info, threadpool_limits
    from style_coanalysis import clustering, graph, pipeline
    seen = {"kmeans": [], "labels": [], "triplets": []}

    def threads():
        return max(p["num_threads"] for p in threadpool_info())

    def recording(key, fn):
        def call(*args, **kwargs):
            seen[key].append(threads())
            return fn(*args, **kwargs)
        return call

    class KMeans(graph.KMeans):               # every cut of the graph is graph.kmeans
        fit = recording("kmeans", graph.KMeans.fit)

    monkeypatch.setattr(graph, "KMeans", KMeans)
    monkeypatch.setattr(pipeline, "_label_transduction",
                        recording("labels", pipeline._label_transduction))
    monkeypatch.setattr(clustering.TripletClustering, "fit_predict",
                        recording("triplets", clustering.TripletClustering.fit_predict))
    drawings, params = collection[0], replace(PARAMS, max_rounds=1)
    encoded = pipeline.encode(drawings, params)
    with threadpool_limits(limits=2):
        assert threads() == 2
        analyse(drawings, params, encoded=encoded)
        analyse(drawings, params, labels=_labels(collection), encoded=encoded)
        analyse(drawings, params, triplets=_triplets(collection, 30), encoded=encoded)
    assert seen["kmeans"] and set(seen["kmeans"]) == {1}
    assert seen["labels"] and set(seen["labels"]) == {1}
    assert seen["triplets"] and set(seen["triplets"]) == {2}


def test_a_cancel_stops_the_labels_cross_validation_between_folds(collection):
    """Choosing the labels' reading refits for every fold of the labelled shapes: each fold is
    a progress step, where a cancel stops the run; there are at most ten folds."""
    drawings, styles, _ = collection
    labels = _labels(collection, share=0.5)
    named = [styles[i] for i, d in enumerate(drawings) if d.name in labels]
    assert min(np.bincount(named)) >= 3          # enough of every style for the cross-validation
    seen = []

    def cancel():
        return any(stage == "read labels" and done >= 2 for stage, done, _ in seen)

    with pytest.raises(Cancelled, match="read labels"):
        analyse(drawings, PARAMS, labels=labels, cancel=cancel,
                progress=lambda *step: seen.append(step))
    folds = [step for step in seen if step[0] == "read labels"]
    assert [done for _, done, _ in folds] == [0, 1, 2]
    assert all(3 <= total <= min(len(labels), LABEL_FOLDS) for _, _, total in folds)


def test_the_labels_name_a_cut_the_same_whatever_its_cluster_numbers(monkeypatch):
    """Labels that place equally many labelled shapes whichever of two namings is taken: the
    naming comes from the graph (each cluster named after the labelled shapes it is most tied
    to), not from the cut's cluster numbers, which a 1e-7 change of coordinates can permute."""
    from style_coanalysis import graph, pipeline
    group = np.repeat([0, 1, 2], 20)
    a = np.where(group[:, None] == group[None, :], 0.5, 0.01)
    a[20, group == 1] = a[group == 1, 20] = 0.9      # strongly tied to group 1
    a[21, group == 1] = a[group == 1, 21] = 0.2      # weakly
    a[40, group == 2] = a[group == 2, 40] = 0.9
    a[41, group == 2] = a[group == 2, 41] = 0.2
    y = np.full(60, -1)
    y[[0, 1]] = 2                  # group 0: both of style 2
    y[[20, 41]] = 0                # style 0: strongly in group 1, weakly in group 2
    y[[40, 21]] = 1                # style 1: strongly in group 2, weakly in group 1 (a tie in
                                   # counts: each of groups 1, 2 holds one label of each)
    cut = group.copy()
    named = []
    for perm in ([0, 1, 2], [0, 2, 1], [1, 0, 2], [2, 1, 0]):
        monkeypatch.setattr(graph, "partition", lambda *args, p=perm: np.asarray(p)[cut])
        named.append(pipeline._named_cut(a, y, 3).tolist())
    assert all(n == named[0] for n in named[1:]), named
    assert named[0] == np.array([2, 0, 1])[group].tolist()


def test_cancel_and_bad_constraints_stop_before_work(collection):
    drawings, _, _ = collection
    calls = []

    def cancel():
        return len(calls) > 3

    with pytest.raises(Cancelled):
        analyse(drawings, PARAMS, progress=lambda *a: calls.append(a), cancel=cancel)
    assert len(calls) == 4
    calls.clear()
    with pytest.raises(InputError, match="'Ghost'"):
        analyse(drawings, PARAMS, labels={"Ghost": "a", drawings[0].name: "b"},
                progress=lambda *a: calls.append(a))
    with pytest.raises(InputError, match="two different styles"):
        analyse(drawings, PARAMS, labels={drawings[0].name: "a"})
    with pytest.raises(InputError, match="contradictory"):
        a, b, c = (d.name for d in drawings[:3])
        analyse(drawings, PARAMS, triplets=[(a, b, c), (a, c, b)])
    assert calls == []                                   # refused before any stage ran


def test_structure_relative_words_cancel_what_structural_look_alikes_share():
    from style_coanalysis.views import look_alikes, structure_relative, style_space
    rng = np.random.default_rng(0)
    n = 60
    group = np.repeat(np.arange(3), 20)                      # structure: 3 builds
    style = np.tile(np.arange(2), 30)                        # style: crosses the builds
    structure = np.eye(3)[group] + 0.05 * rng.random((n, 3))
    words = 3.0 * np.eye(3)[group] @ rng.random((3, 8))      # build words, strong
    words[:, :2] += 0.5 * np.eye(2)[style]                   # ornament words, weak
    words += 0.05 * rng.random(words.shape)
    r, = structure_relative(words, look_alikes(structure, 10), [10])
    assert np.abs(r[:, 2:]).mean() < 0.2 * np.abs(words[:, 2:] - words[:, 2:].mean(0)).mean()
    sp = style_space(r, 2)
    from sklearn.cluster import KMeans
    lab = KMeans(2, n_init=5, random_state=0).fit_predict(sp)
    assert purity(lab, style) == 1.0
    lab_raw = KMeans(2, n_init=5, random_state=0).fit_predict(words)
    assert purity(lab_raw, style) < 0.8                      # raw words follow the builds
    # with the whole collection as look-alikes it is plain centring
    centred, = structure_relative(words, look_alikes(structure, 4), [n - 1])
    np.testing.assert_allclose(centred, words - words.mean(0))


def test_look_alike_means_match_a_direct_computation_across_row_blocks():
    """The blocked ladder gives each rung's mean over exactly the k nearest structural
    neighbours, or, past RUNG_SAMPLE of them, over RUNG_SAMPLE spread evenly by rank from the
    nearest to the k-th (a collection larger than one block of rows), word by word."""
    from sklearn.metrics import pairwise_distances
    from style_coanalysis.views import (BLOCK, RUNG_SAMPLE, look_alikes, neighbour_ladder,
                                        rung_ranks, structure_relative)
    rng = np.random.default_rng(3)
    n = BLOCK + 77
    layout, words = rng.random((n, 6)), rng.random((n, 9))
    ks = neighbour_ladder(n)
    assert max(k for k in ks if k < n - 1) > RUNG_SAMPLE >= min(ks)
    near = look_alikes(layout, max(k for k in ks if k < n - 1))
    s = (layout - layout.mean(0)) / layout.std(0)
    d = pairwise_distances(s)
    np.fill_diagonal(d, np.inf)
    order = np.argsort(d, axis=1)
    for k, r in zip(ks, structure_relative(words, near, ks)):
        ranks = rung_ranks(k)
        assert len(ranks) == min(k, RUNG_SAMPLE) and ranks[0] == 0 and ranks[-1] == k - 1
        assert np.all(np.diff(ranks) > 0)
        expect = words - (words[order[:, ranks]].mean(axis=1) if k < n - 1 else words.mean(0))
        np.testing.assert_allclose(r, expect, atol=1e-9)
    # the rounds keep some words and slice the rungs computed once: the same as the rungs of
    # the kept words alone
    keep = rng.random(words.shape[1]) < 0.5
    for whole, kept in zip(structure_relative(words, near, ks),
                           structure_relative(words[:, keep], near, ks)):
        np.testing.assert_allclose(whole[:, keep], kept, rtol=0, atol=1e-12)


def test_the_neighbour_ladder_spans_the_same_fractions_of_every_collection():
    """The ladder halves from the whole collection: down to a handful of look-alikes in a
    small collection, down to N/16 in a large one, so a larger collection of the same make-up
    gets the same views rather than more rungs of near copies."""
    from style_coanalysis.views import LADDER_RUNGS, MIN_NEIGHBOURS, neighbour_ladder
    for n in (2, 6, 24, 120, 537, 5000):
        ks = neighbour_ladder(n)
        assert ks[0] == n - 1 and all(a > b for a, b in zip(ks, ks[1:]))
        assert min(ks) >= min(MIN_NEIGHBOURS, n - 1) and len(ks) <= LADDER_RUNGS
        assert min(ks) < 2 * MIN_NEIGHBOURS or len(ks) == LADDER_RUNGS
    assert neighbour_ladder(5000)[-1] == round(4999 / 2 ** (LADDER_RUNGS - 1))
    assert neighbour_ladder(120) == [119, 60, 30, 15, 7]


def test_encoding_reads_the_shapes_one_at_a_time(collection):
    """`encode` needs no list of drawings nor every map at once: given a sequence that makes each
    shape on access, it gives the encoding of the same shapes held in memory with their maps."""
    from style_coanalysis.features import collection_maps
    from style_coanalysis.pipeline import encode
    drawings, _, _ = collection

    class OnAccess:
        reads = 0

        def __len__(self):
            return len(drawings)

        def __getitem__(self, i):
            if not 0 <= i < len(drawings):
                raise IndexError(i)
            OnAccess.reads += 1
            return drawings[i]

    lazy = encode(OnAccess(), PARAMS)
    held = encode(drawings, PARAMS, maps=collection_maps(drawings))
    assert OnAccess.reads == len(drawings)               # one pass over the drawings
    np.testing.assert_array_equal(lazy.lines, held.lines)
    assert len(lazy.dictionaries) == len(held.dictionaries) == PARAMS.n_dictionaries
    for a, b in zip(lazy.dictionaries, held.dictionaries):
        for field in ("rungs", "relative"):
            np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


def test_dictionaries_are_independent_draws_and_the_first_is_the_seeds(collection):
    """Each dictionary is its own draw; the first is the one a single-dictionary analysis draws,
    and it is the one the result reports (its words mark the meshes). The views of all of them
    fuse into one graph whose view weights are reported once per kind of view."""
    from style_coanalysis.features import collection_maps
    from style_coanalysis.pipeline import encode
    drawings, _, _ = collection
    maps = collection_maps(drawings)
    one = encode(drawings, replace(PARAMS, n_dictionaries=1), maps=maps)
    three = encode(drawings, replace(PARAMS, n_dictionaries=3), maps=maps)
    assert len(one.dictionaries) == 1 and len(three.dictionaries) == 3
    np.testing.assert_array_equal(one.dictionaries[0].bank.hog, three.dictionaries[0].bank.hog)
    np.testing.assert_array_equal(one.dictionaries[0].rungs, three.dictionaries[0].rungs)
    hogs = [d.bank.hog for d in three.dictionaries]
    assert not np.array_equal(hogs[0], hogs[1]) and not np.array_equal(hogs[1], hogs[2])
    # each is cut at its own patch size: the first at `patch_size`, then the others in turn
    sizes = [PARAMS.dictionary_patch_size(m) for m in range(5)]
    assert sizes == [PARAMS.patch_size, *PARAMS.other_patch_sizes, PARAMS.patch_size,
                     PARAMS.other_patch_sizes[0]] and len(set(sizes)) == 3
    assert [h.shape[1] for h in hogs] == [patch_blocks(s) for s in sizes[:3]]
    same = encode(drawings, replace(PARAMS, n_dictionaries=3, other_patch_sizes=()), maps=maps)
    assert {d.bank.hog.shape[1] for d in same.dictionaries} == {patch_blocks(PARAMS.patch_size)}
    np.testing.assert_array_equal(same.dictionaries[0].rungs, three.dictionaries[0].rungs)

    result = analyse(drawings, replace(PARAMS, n_dictionaries=3), maps=maps, encoded=three)
    np.testing.assert_array_equal(result.words, three.dictionaries[0].bank.hog)
    assert len(result.view_names) == len(result.view_weights) == len(set(result.view_names))
    assert result.view_names[-1] == "line character"
    assert result.view_weights.sum() == pytest.approx(1.0)


def test_labels_the_unsupervised_cut_honours_change_only_its_names():
    """Few labels (two per style) that agree with the graph's own cut: the result is that cut,
    its clusters named by the labels, not the partition the labelled means start k-means to."""
    from style_coanalysis import graph
    from style_coanalysis.pipeline import _label_transduction, _seeded_cut, _unit_coordinates
    rng = np.random.default_rng(1)
    x = rng.uniform(0, 1, (90, 2))                  # no clear groups: many cuts nearly as good
    a = graph.affinity(x)
    own = graph.partition(a, 4, 0)
    coords = _unit_coordinates(a, 4)
    styles = np.array([2, 0, 3, 1])                 # style numbers unrelated to the clusters'
    y = np.full(90, -1)
    for c in range(4):                              # each cluster's two shapes farthest out
        m = np.flatnonzero(own == c)
        far = np.argsort(-np.linalg.norm(coords[m] - coords[m].mean(axis=0), axis=1))[:2]
        y[m[far]] = styles[c]
    classes, _, _ = _label_transduction(a, x, y, 4, 0)
    assert classes.tolist() == styles[own].tolist()
    seeded = _seeded_cut(coords, y, 4)
    assert not np.array_equal(seeded, styles[own])  # the seeded cut alone moves some shapes


@pytest.mark.parametrize("picked, margin, reading", [
    ([55, 10, 37, 40, 36, 19, 33, 83], 1, "own"),
    ([31, 6, 69, 75, 88, 47, 82, 44], 2, "seeded")])
def test_few_labels_move_the_cut_only_when_it_misplaces_two_more(picked, margin, reading):
    """Two labels per style where the graph's own cut misplaces some: the seeded cut replaces
    it only if it places at least two more labelled shapes in their style (one more is noise);
    either way the labelled shapes keep their labels."""
    from style_coanalysis import graph
    from style_coanalysis.pipeline import (_label_transduction, _named_cut, _seeded_cut,
                                           _unit_coordinates)
    rng = np.random.default_rng(1)
    x = rng.uniform(0, 1, (90, 2))                  # no clear groups: many cuts nearly as good
    a = graph.affinity(x)
    y = np.full(90, -1)
    y[picked] = [0, 0, 1, 1, 2, 2, 3, 3]
    cuts = {"own": _named_cut(a, y, 4, 0), "seeded": _seeded_cut(_unit_coordinates(a, 4), y, 4)}
    placed = {k: int((c[picked] == y[picked]).sum()) for k, c in cuts.items()}
    assert placed["seeded"] - placed["own"] == margin     # the case this parameter stands for
    classes, _, used = _label_transduction(a, x, y, 4, 0)
    assert used == reading
    expected = cuts[reading].copy()
    expected[picked] = y[picked]
    assert classes.tolist() == expected.tolist()


def test_labels_place_the_centres_and_name_the_clusters_whatever_the_order():
    """Two labels per style in three separated groups: every shape gets its group's style (the
    names come from the labels, not from the cluster numbers), and a reordered input gives the
    same classes, reordered."""
    from style_coanalysis import graph
    from style_coanalysis.pipeline import _label_transduction
    rng = np.random.default_rng(3)
    group = np.repeat([0, 1, 2], 20)
    x = np.array([[0.0, 0.0], [6.0, 0.0], [0.0, 6.0]])[group] + rng.normal(0, 0.7, (60, 2))
    style_of_group = np.array([2, 0, 1])            # style numbers unrelated to the groups'
    y = np.full(60, -1)
    for g in range(3):
        y[np.flatnonzero(group == g)[:2]] = style_of_group[g]
    classes, dist, _ = _label_transduction(graph.affinity(x), x, y, 3)
    assert classes.tolist() == style_of_group[group].tolist()
    assert np.allclose(dist.sum(axis=1), 1.0)
    order = rng.permutation(60)
    again, _, _ = _label_transduction(graph.affinity(x[order]), x[order], y[order], 3)
    assert again.tolist() == classes[order].tolist()


def test_the_labels_folds_follow_the_shapes_and_leave_every_style_two_to_fit():
    from style_coanalysis.pipeline import _label_folds
    rng = np.random.default_rng(0)
    assert [list(f) for f in _label_folds(rng.normal(size=(9, 4)), np.repeat([0, 1, 2], 3), 3)] \
        == [[i] for i in range(9)]                          # leave-one-out up to ten labels
    x, y = rng.normal(size=(47, 4)), np.repeat([0, 1, 2], [20, 3, 24])
    folds = _label_folds(x, y, 3)
    assert len(folds) == LABEL_FOLDS and sorted(np.concatenate(folds)) == list(range(47))
    assert all(np.bincount(y[f], minlength=3).max() <= 3 for f in folds)
    assert all((np.bincount(y, minlength=3) - np.bincount(y[f], minlength=3)).min() >= 2
               for f in folds)
    few = _label_folds(rng.normal(size=(12, 4)), np.repeat([0, 1, 2, 3], 3), 4)
    assert [len(f) for f in few] == [4, 4, 4]               # no fold that hides nothing
    p = rng.permutation(47)
    again = _label_folds(x[p], y[p], 3)                     # the same shapes in another order
    assert sorted(sorted(p[f]) for f in again) == sorted(sorted(f) for f in folds)
