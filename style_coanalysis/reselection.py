"""Cluster-guided patch reselection (paper 4.5, eq. 4): keep filters frequent in one cluster only.

What eq. 4 means to do: a filter is "discriminant" for cluster l when the shapes of l support it
much more than the collection as a whole does. Evaluated literally as printed, its weights
(x_li / C - 1/N_p) and threshold (mu N_p / C) keep nearly every filter on real data, so nothing is
selected. We implement the intent:

* support s_ij of shape i for filter j: the percentile rank (0..1, ties averaged) of the filter's
  whole-image max response in shape i among all shapes. Soft and free of an arbitrary response
  threshold; a filter every shape answers equally has s = 0.5 everywhere.
* score  delta_lj = mean_{i in l} s_ij - mean_i s_ij   (eq. 4's signed in-minus-out support).
* threshold  delta_l^t = mu * sqrt(N / n_l). The mean of n_l ranks drawn at random fluctuates by
  about sqrt((1/12)(1/n_l - 1/N)), i.e. proportionally to 1/sqrt(n_l); scaling by sqrt(N/n_l)
  keeps the threshold about 3 of those fluctuations for usual cluster sizes, so small clusters
  do not pass on noise, while mu (0.07, paper) still sets the required effect size.
* kept set = union over clusters; each kept filter records the cluster where score/threshold
  is highest (the style it characterises) and that score. Every view keeps at least
  `min_per_view` filters (the best by score/threshold), so no view's feature becomes empty.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.stats import rankdata

MIN_PER_VIEW = 5


@dataclass
class Reselection:
    keep: np.ndarray           # (F,) bool
    cluster: np.ndarray        # (F,) int, best-discriminated cluster (-1 if none passed)
    score: np.ndarray          # (F,) float, delta of that cluster
    scores: np.ndarray         # (C, F) every delta_lj
    thresholds: np.ndarray     # (C,)
    n_passed: int              # filters above a threshold, before the per-view minimum
    per_view: dict = field(default_factory=dict)   # view -> number kept


def support(responses: np.ndarray) -> np.ndarray:
    """Percentile rank of each shape's response per filter: (N, F) in [0, 1]."""
    n = len(responses)
    if n < 2:
        return np.full(responses.shape, 0.5)
    return (rankdata(responses, axis=0, method="average") - 1.0) / (n - 1.0)


def reselect(responses: np.ndarray, clusters: np.ndarray, filter_view: np.ndarray,
             mu: float = 0.07, min_per_view: int = MIN_PER_VIEW) -> Reselection:
    """Select discriminant filters given shape clusters.

    responses: (N, F) whole-image max response of each filter (in its own view) per shape;
    clusters: (N,) cluster ids; filter_view: (F,) view of each filter.
    """
    responses = np.asarray(responses, np.float64)
    clusters = np.asarray(clusters)
    filter_view = np.asarray(filter_view)
    n, f = responses.shape
    ids = np.unique(clusters)
    s = support(responses)
    overall = s.mean(axis=0)
    sizes = np.array([(clusters == c).sum() for c in ids], np.float64)
    scores = np.stack([s[clusters == c].mean(axis=0) - overall for c in ids]) if f else \
        np.zeros((len(ids), 0))
    thresholds = mu * np.sqrt(n / sizes)
    if len(ids) < 2:                        # one cluster: nothing to discriminate, keep all
        return Reselection(np.ones(f, bool), np.full(f, -1), np.zeros(f), scores, thresholds, f,
                           {int(v): int((filter_view == v).sum()) for v in np.unique(filter_view)})
    ratio = scores / thresholds[:, None]
    best = ratio.argmax(axis=0)
    keep = ratio.max(axis=0) > 1.0
    n_passed = int(keep.sum())
    best_ratio = ratio.max(axis=0)
    for v in np.unique(filter_view):
        idx = np.flatnonzero(filter_view == v)
        short = min(min_per_view, len(idx)) - int(keep[idx].sum())
        if short > 0:
            extra = idx[~keep[idx]]
            keep[extra[np.argsort(-best_ratio[extra], kind="stable")[:short]]] = True
    cluster = np.where(best_ratio > 1.0, ids[best], -1)
    score = scores[best, np.arange(f)]
    per_view = {int(v): int(keep[filter_view == v].sum()) for v in np.unique(filter_view)}
    return Reselection(keep, cluster, score, scores, thresholds, n_passed, per_view)
