"""Evaluation measures (paper section 5): cluster purity (eq. 5), NMI, ARI and triplet accuracy.

Kept apart from the analysis so tests, benchmarks and the command line score results the same way.
"""
from __future__ import annotations

import numpy as np
from sklearn.metrics import adjusted_rand_score, normalized_mutual_info_score
from sklearn.metrics.cluster import contingency_matrix


def purity(pred, truth) -> float:
    """Eq. 5: each cluster votes for its majority true class; fraction of shapes in the majority."""
    pred, truth = np.asarray(pred), np.asarray(truth)
    if len(pred) != len(truth):
        raise ValueError(f"{len(pred)} predictions for {len(truth)} labels")
    if len(pred) == 0:
        return float("nan")
    c = contingency_matrix(truth, pred)
    return float(c.max(axis=0).sum() / c.sum())


def nmi(pred, truth) -> float:
    return float(normalized_mutual_info_score(truth, pred))


def ari(pred, truth) -> float:
    return float(adjusted_rand_score(truth, pred))


def triplet_accuracy(distance_matrix, triplets) -> float:
    """Share of triplets (a, b, c) - "a is closer in style to b than to c" - that the distances
    agree with (D[a, b] < D[a, c]); ties count half, as a coin toss would."""
    D = np.asarray(distance_matrix, dtype=np.float64)
    t = np.asarray(triplets, dtype=np.int64).reshape(-1, 3)
    if len(t) == 0:
        return float("nan")
    ab, ac = D[t[:, 0], t[:, 1]], D[t[:, 0], t[:, 2]]
    return float(((ab < ac) + 0.5 * (ab == ac)).mean())


def score(pred, truth) -> dict:
    """All clustering measures of one result, plus the chance level of purity for balanced classes."""
    pred, truth = np.asarray(pred), np.asarray(truth)
    _, counts = np.unique(truth, return_counts=True)
    return {"purity": purity(pred, truth), "nmi": nmi(pred, truth), "ari": ari(pred, truth),
            "n_clusters": int(len(np.unique(pred))), "n_classes": int(len(counts)),
            "majority_share": float(counts.max() / counts.sum())}
