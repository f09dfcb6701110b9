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


def region_scores(pred_masks, true_masks, areas=None, seed: int = 0) -> dict:
    """Precision / recall / IoU of predicted style faces against the true decorative faces.

    Counted per face and, when `areas` are given, weighted by face area (the sample's ornaments
    are finely tessellated, so by count most faces are decorative and precision is flattered).
    `random_*` is the baseline the numbers must beat: the same number of faces per shape, drawn
    at random (seeded).
    """
    rng = np.random.default_rng(seed)
    tot = {k: np.zeros(3) for k in ("count", "area", "random_count", "random_area")}
    for i, (pred, true) in enumerate(zip(pred_masks, true_masks)):
        pred, true = np.asarray(pred, bool), np.asarray(true, bool)
        rand = np.zeros_like(pred)
        rand[rng.choice(len(pred), int(pred.sum()), replace=False)] = True
        w = np.ones(len(pred)) if areas is None else np.asarray(areas[i], float)
        for key, p in (("count", pred), ("random_count", rand)):
            tot[key] += [np.sum(p & true), np.sum(p & ~true), np.sum(~p & true)]
        for key, p in (("area", pred), ("random_area", rand)):
            tot[key] += [w[p & true].sum(), w[p & ~true].sum(), w[~p & true].sum()]
    out = {}
    for key, (tp, fp, fn) in tot.items():
        if areas is None and "area" in key:
            continue
        out[key] = {"precision": float(tp / max(tp + fp, 1e-12)), "recall": float(tp / max(tp + fn, 1e-12)),
                    "iou": float(tp / max(tp + fp + fn, 1e-12))}
    return out
