"""Cluster-guided word reselection (paper 4.5, eq. 4): keep the words frequent in one cluster only.

What eq. 4 means to do: a word ("filter") is discriminant for cluster l when the shapes of l
support it much more than the collection as a whole does. Evaluated literally as printed, its
weights (x_li / C - 1/N_p) and threshold (mu N_p / C) keep nearly every word on real data, so
nothing is selected. We implement the intent:

* support s_ij of shape i for word j: the percentile rank (0..1, ties averaged) of the shape's
  profile value for the word among all shapes; the pipeline passes each dictionary's word
  profile relative to the shapes' structural look-alikes (`pipeline.Dictionary.relative`), so a
  word is supported where a shape has more of it than its look-alikes. Soft and free of an
  arbitrary threshold; a word every shape has equally has s = 0.5 everywhere.
* score  delta_lj = mean_{i in l} s_ij - mean_i s_ij   (eq. 4's signed in-minus-out support).
* threshold  delta_l^t = mu * sqrt(N / n_l). The mean of n_l ranks drawn at random fluctuates by
  about sqrt((1/12)(1/n_l - 1/N)), i.e. proportionally to 1/sqrt(n_l); scaling by sqrt(N/n_l)
  keeps the threshold about 3 of those fluctuations for usual cluster sizes, so small clusters
  do not pass on noise, while mu (0.07, paper) still sets the required effect size.
* kept set = union over clusters; each kept word records the cluster where score/threshold is
  highest (the style it characterises) and that score. At least `min_kept` words are kept (the
  best by score/threshold), so the style graph's views never become empty.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import rankdata

MIN_KEPT = 5


@dataclass
class Reselection:
    keep: np.ndarray           # (F,) bool
    cluster: np.ndarray        # (F,) int, best-discriminated cluster (-1 if none passed)
    score: np.ndarray          # (F,) float, delta of that cluster
    scores: np.ndarray         # (C, F) every delta_lj
    thresholds: np.ndarray     # (C,)
    n_passed: int              # words above a threshold, before the minimum kept


def support(profiles: np.ndarray) -> np.ndarray:
    """Percentile rank of each shape's value per word: (N, F) in [0, 1]."""
    n = len(profiles)
    if n < 2:
        return np.full(profiles.shape, 0.5)
    return (rankdata(profiles, axis=0, method="average") - 1.0) / (n - 1.0)


def reselect(profiles: np.ndarray, clusters: np.ndarray, mu: float = 0.07,
             min_kept: int = MIN_KEPT) -> Reselection:
    """Select the words that discriminate the given shape clusters.

    profiles: (N, F) each shape's value per word; clusters: (N,) cluster ids.
    """
    profiles = np.asarray(profiles, np.float64)
    clusters = np.asarray(clusters)
    n, f = profiles.shape
    ids = np.unique(clusters)
    s = support(profiles)
    overall = s.mean(axis=0)
    sizes = np.array([(clusters == c).sum() for c in ids], np.float64)
    scores = np.stack([s[clusters == c].mean(axis=0) - overall for c in ids]) if f else \
        np.zeros((len(ids), 0))
    thresholds = mu * np.sqrt(n / sizes)
    if len(ids) < 2:                        # one cluster: nothing to discriminate, keep all
        return Reselection(np.ones(f, bool), np.full(f, -1), np.zeros(f), scores, thresholds, f)
    ratio = scores / thresholds[:, None]
    best = ratio.argmax(axis=0)
    keep = ratio.max(axis=0) > 1.0
    n_passed = int(keep.sum())
    best_ratio = ratio.max(axis=0)
    short = min(min_kept, f) - n_passed
    if short > 0:
        extra = np.flatnonzero(~keep)
        keep[extra[np.argsort(-best_ratio[extra], kind="stable")[:short]]] = True
    cluster = np.where(best_ratio > 1.0, ids[best], -1)
    score = scores[best, np.arange(f)]
    return Reselection(keep, cluster, score, scores, thresholds, n_passed)
