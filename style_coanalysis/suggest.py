"""What to label next: rank unlabelled shapes by how much a style label on them should help.

Why this order. In label mode the analysis has one cluster per style named by the labels, so a
style nobody labelled cannot appear at all: the first picks cover the clusters that hold no
label yet, each by its most typical member (its medoid in the style space), largest cluster
first. Then the labels go where the analysis is unsure (low confidence) among shapes that are
typical of many others (high local density, so one label speaks for a neighbourhood and not for
an outlier), each pick spread away from the labelled shapes and from the earlier picks (a label
next to a known one says little new). Measured against random picks by
`bench/bench_suggest.py`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .meshes import InputError
from .similarity import StyleSpace


@dataclass
class Suggestion:
    name: str
    cluster: int
    confidence: float
    score: float
    reason: str


def _density(D: np.ndarray) -> np.ndarray:
    """exp(-mean distance to the nearest neighbours / its median): 1 is typical, -> 0 outliers.
    The neighbour count grows with the collection (sqrt N), so no size is fixed."""
    n = len(D)
    m = int(np.clip(round(np.sqrt(n)), 1, n - 1))
    near = np.sort(D + np.diag(np.full(n, np.inf)), axis=1)[:, :m].mean(axis=1)
    return np.exp(-near / max(float(np.median(near)), 1e-12))


def suggest(space: StyleSpace, n: int, labelled=None) -> list[Suggestion]:
    """The `n` shapes to label next, best first. `labelled` (N,) bool: shapes that carry a label
    now (default: those labelled in the analysis); they are never suggested."""
    N = len(space.names)
    if n < 1:
        raise InputError(f"the number of shapes to suggest must be at least 1, got {n}")
    done = np.asarray(space.label_given if labelled is None else labelled, bool).copy()
    if len(done) != N:
        raise ValueError("labelled must have one entry per shape")
    free = np.flatnonzero(~done)
    if len(free) == 0:
        raise InputError("every analysed shape is labelled already: nothing to suggest")
    D = space.distance_matrix()
    dens = _density(D)
    scale = max(float(np.median(D[np.triu_indices(N, 1)])), 1e-12) if N > 1 else 1.0
    picks: list[Suggestion] = []
    taken = done.copy()

    # 1. coverage: clusters with no label, largest first, by their medoid
    ids, sizes = np.unique(space.clusters, return_counts=True)
    for c in ids[np.argsort(-sizes, kind="stable")]:
        if len(picks) == n:
            break
        members = np.flatnonzero(space.clusters == c)
        if taken[members].any():
            continue
        medoid = members[np.argmin(D[np.ix_(members, members)].mean(axis=1))]
        taken[medoid] = True
        picks.append(Suggestion(space.names[medoid], int(c), float(space.confidence[medoid]),
                                1.0 + float(dens[medoid]),
                                f"cluster {int(c)} ({len(members)} shapes) has no label yet: "
                                "its most typical shape"))

    # 2. uncertain and typical, away from what is known
    while len(picks) < n and not taken.all():
        cand = np.flatnonzero(~taken)
        known = np.flatnonzero(taken)
        spread = (np.clip(D[np.ix_(cand, known)].min(axis=1) / scale, 0, 1) if len(known)
                  else np.ones(len(cand)))
        unsure = 1.0 - space.confidence[cand]
        score = unsure * dens[cand] * spread
        k = int(np.argmax(score))
        i = int(cand[k])
        taken[i] = True
        picks.append(Suggestion(space.names[i], int(space.clusters[i]),
                                float(space.confidence[i]), float(score[k]),
                                f"the analysis is unsure (confidence {space.confidence[i]:.2f}) "
                                f"of a typical shape (density {dens[i]:.2f}) far from the "
                                f"labelled ones (spread {spread[k]:.2f})"))
    return picks
