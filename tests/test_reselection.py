"""Reselection really selects: a planted discriminative filter stays, a common one goes."""
import numpy as np

from style_coanalysis.reselection import reselect


def _collection(rng, n_per=20, n_clusters=3, n_noise=40):
    clusters = np.repeat(np.arange(n_clusters), n_per)
    n = len(clusters)
    resp = [rng.uniform(0.3, 0.7, (n, n_noise))]                  # uninformative filters
    planted = np.where(clusters == 1, 0.9, 0.4) + 0.05 * rng.standard_normal(n)
    frequent = 0.95 + 0.02 * rng.standard_normal(n)                # everyone has it
    constant = np.full(n, 0.8)
    resp = np.column_stack(resp + [planted, frequent, constant])
    return resp, clusters


def test_keeps_planted_drops_frequent_and_records_cluster():
    rng = np.random.default_rng(0)
    resp, clusters = _collection(rng)
    f = resp.shape[1]
    view = np.zeros(f, int)
    sel = reselect(resp, clusters, view, mu=0.07, min_per_view=1)
    planted, frequent, constant = f - 3, f - 2, f - 1
    assert sel.keep[planted] and sel.cluster[planted] == 1 and sel.score[planted] > 0.2
    assert not sel.keep[frequent] and not sel.keep[constant]
    assert sel.n_passed < f // 4                                   # noise mostly dropped
    assert sel.per_view == {0: int(sel.keep.sum())}


def test_minimum_per_view_and_cluster_labels_are_arbitrary_ids():
    rng = np.random.default_rng(1)
    resp, clusters = _collection(rng)
    f = resp.shape[1]
    view = np.arange(f) % 4                                        # the planted one is in view 3
    sel = reselect(resp, clusters * 10 + 5, view, mu=0.07, min_per_view=6)
    assert all(sel.keep[view == v].sum() >= 6 for v in range(4))
    assert sel.cluster[f - 3] == 15
    # a looser mu keeps at least as many; no clusters to tell apart keeps everything
    assert reselect(resp, clusters, view, mu=0.02).keep.sum() >= sel.keep.sum()
    assert reselect(resp, np.zeros(len(clusters), int), view).keep.all()
