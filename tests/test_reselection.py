"""Reselection really selects: a planted discriminative word stays, a common one goes."""
import numpy as np

from style_coanalysis.reselection import reselect


def _collection(rng, n_per=20, n_clusters=3, n_noise=40):
    clusters = np.repeat(np.arange(n_clusters), n_per)
    n = len(clusters)
    profiles = [rng.uniform(0.3, 0.7, (n, n_noise))]               # uninformative words
    planted = np.where(clusters == 1, 0.9, 0.4) + 0.05 * rng.standard_normal(n)
    frequent = 0.95 + 0.02 * rng.standard_normal(n)                # everyone has it
    constant = np.full(n, 0.8)
    profiles = np.column_stack(profiles + [planted, frequent, constant])
    return profiles, clusters


def test_keeps_planted_drops_frequent_and_records_cluster():
    rng = np.random.default_rng(0)
    profiles, clusters = _collection(rng)
    f = profiles.shape[1]
    sel = reselect(profiles, clusters, mu=0.07, min_kept=1)
    planted, frequent, constant = f - 3, f - 2, f - 1
    assert sel.keep[planted] and sel.cluster[planted] == 1 and sel.score[planted] > 0.2
    assert not sel.keep[frequent] and not sel.keep[constant]
    assert sel.n_passed < f // 4                                   # noise mostly dropped
    assert sel.keep.sum() == sel.n_passed                          # the minimum added none


def test_minimum_kept_and_cluster_labels_are_arbitrary_ids():
    rng = np.random.default_rng(1)
    profiles, clusters = _collection(rng)
    f = profiles.shape[1]
    sel = reselect(profiles, clusters * 10 + 5, mu=0.07, min_kept=f // 2)
    assert sel.n_passed < f // 2 and sel.keep.sum() == f // 2      # topped up to the minimum
    # the words added are the best of those that did not pass
    ratio = (sel.scores / sel.thresholds[:, None]).max(axis=0)
    assert ratio[sel.keep].min() >= ratio[~sel.keep].max()
    assert sel.cluster[f - 3] == 15
    # a looser mu keeps at least as many; no clusters to tell apart keeps everything
    assert reselect(profiles, clusters, mu=0.02).keep.sum() >= \
        reselect(profiles, clusters, mu=0.07).keep.sum()
    assert reselect(profiles, np.zeros(len(clusters), int)).keep.all()
