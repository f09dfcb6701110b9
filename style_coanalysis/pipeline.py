"""The whole analysis in one call (paper 4.1-4.5): drawings in, style clusters and style filters out.

    patches -> HOG maps -> representatives (one dictionary for all views, 24 px)
    -> frequency encoding -> structure residual -> style space -> [fuse -> cluster -> reselect]*

Departures from the paper, each measured on the 120-shape sample (bench/bench_unsupervised.py):
the per-view, max- and quadrant-pooled 48 px encoding clustered by category (style purity 0.25,
category 0.80). Style is what recurs across structurally different shapes, so each shape's
small-patch word frequencies are compared with those of its structural neighbours (found with a
48 px "layout" dictionary, no labels), see `structure_residual`. The number of clusters is chosen
by silhouette on the style space (`choose_n_clusters`). PSLF then fuses the style space given as
two non-negative views (its positive and negative parts), unscaled.

The bracket is the cluster-and-select loop of 4.5: reselection scores each style filter by its
residual in each cluster (eq. 4 intent) and the next round's style space uses the kept filters
only (a column selection). Reselection picks from the whole candidate pool every round, so a
filter dropped on the strength of an early, poor clustering can come back. The loop stops when
neither the clusters (up to a renaming) nor the filter set change, after a repeated state, or
after `params.max_rounds` rounds. Constraints (labels or triplets) act in every round's
clustering. Nothing here reads ground truth.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from .constraints import labels_to_array, triplets_to_array, validate_labels, validate_triplets
from .drawings import ShapeDrawings
from .encoding import cross_view_responses, frequency_features, shared_bank, word_counts
from .features import hog_images
from .meshes import InputError
from .params import AnalysisParams
from .patches import extract_patches
from .progress import Progress
from .reselection import reselect

FUSIONS = ("pslf", "concat", "pca", "cca", "maxpool")


@dataclass
class StyleFilter:
    """A kept filter: a real patch (source shape/seed/pixel in its view) and the style it marks."""

    cluster: int
    view: int
    hog: np.ndarray
    source_shape: int
    source_seed: int
    source_pixel: tuple[float, float]
    score: float


@dataclass
class AnalysisResult:
    names: list[str]
    clusters: np.ndarray            # (N,) int 0..C-1
    n_clusters: int
    fused: np.ndarray               # (N, D)
    confidence: np.ndarray          # (N,) in [0, 1]
    classes: list[str] | None       # label mode: style names, cluster c <-> classes[c]
    predicted: list[str] | None     # label mode: predicted (or given) style per shape
    label_given: np.ndarray         # (N,) bool
    style_filters: list[StyleFilter]
    responses: np.ndarray           # (N, V, F) whole-image max response of final filter f in view v
    view_weights: np.ndarray | None
    rounds: list[dict] = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    words: np.ndarray | None = None          # (K, nb, nb, C) the whole dictionary (unit HOG)
    word_cluster: np.ndarray | None = None   # (K,) the cluster a word is a style filter of, or -1
    word_score: np.ndarray | None = None     # (K,) its discriminant score (-inf for other words)


def _check_inputs(drawings, params, labels, triplets, fusion):
    """Refuse bad input before any work: nothing runs half-way."""
    if fusion not in FUSIONS:
        raise InputError(f"unknown fusion '{fusion}', choose one of {', '.join(FUSIONS)}")
    if len(drawings) < 2:
        raise InputError(f"need at least two shapes to analyse, got {len(drawings)}")
    names = [d.name for d in drawings]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise InputError("shape names must be unique: " + ", ".join(f"'{n}'" for n in dup))
    shapes = {tuple(d.images.shape) for d in drawings}
    if len(shapes) != 1:
        raise InputError(f"all shapes need the same number and size of views, got {sorted(shapes)}")
    if labels is not None and triplets is not None:
        raise InputError("give either style labels or triplets, not both")
    if params.n_clusters is not None and params.n_clusters < 1:
        raise InputError(f"number of clusters must be at least 1, got {params.n_clusters}")
    y = classes = trip = None
    if labels is not None:
        validate_labels(labels)
        y, classes = labels_to_array(labels, names)
    if triplets is not None:
        validate_triplets(triplets)
        trip = triplets_to_array(triplets, names)
    return names, y, classes, trip


def _relabel_by_appearance(labels: np.ndarray) -> np.ndarray:
    """Cluster ids 0..C-1 in order of first appearance: same partition, stable names."""
    _, first = np.unique(labels, return_index=True)
    order = np.unique(labels)[np.argsort(first)]
    lut = {c: i for i, c in enumerate(order)}
    return np.array([lut[c] for c in labels], np.int64)


def n_changed(old: np.ndarray | None, new: np.ndarray) -> int:
    """Shapes whose cluster changed, after the best one-to-one renaming of clusters."""
    if old is None:
        return int(len(new))
    a, b = np.unique(old, return_inverse=True)[1], np.unique(new, return_inverse=True)[1]
    table = np.zeros((a.max() + 1, b.max() + 1), np.int64)
    np.add.at(table, (a, b), 1)
    r, c = linear_sum_assignment(-table)
    return int(len(new) - table[r, c].sum())


def _partition_key(labels: np.ndarray) -> bytes:
    """The partition independent of cluster names."""
    return _relabel_by_appearance(np.asarray(labels)).astype(np.int64).tobytes()


def _soft_confidence(x: np.ndarray, clusters: np.ndarray) -> np.ndarray:
    """Membership of the assigned cluster from squared distances to cluster means (softmax).

    The temperature is the mean squared distance of shapes to their own centre, so a shape at a
    typical distance from its centre and far from the others gets a confidence near 1.
    """
    ids = np.unique(clusters)
    centres = np.stack([x[clusters == c].mean(axis=0) for c in ids])
    d2 = ((x[:, None, :] - centres[None]) ** 2).sum(axis=2)
    own = d2[np.arange(len(x)), np.searchsorted(ids, clusters)]
    temp = max(float(own.mean()), 1e-12)
    logits = -(d2 - d2.min(axis=1, keepdims=True)) / temp
    p = np.exp(logits)
    p /= p.sum(axis=1, keepdims=True)
    return p[np.arange(len(x)), np.searchsorted(ids, clusters)]


def _fuse(views, params, y, fusion):
    """Fused features (N, D) and view weights (or None)."""
    views = [v for v in views if v.shape[1] > 0]
    if fusion == "pslf":
        from .pslf import PSLF
        model = PSLF(n_components=params.n_components, eta=params.eta, lam=params.lam,
                     beta=params.beta, gamma=params.gamma, random_state=params.random_state,
                     scaling="none")   # the style-space views are already on one scale (see
        # _fusion_views); PSLF's default per-feature min-max stretched noise directions: measured
        # on the sample, spectral k=4 style purity 0.74 with 'auto', 0.89 with 'none'
        fused = model.fit_transform(views, y=y)
        return fused, np.asarray(model.view_weights_)
    from . import fusion as fusion_mod
    cls = {"concat": "ConcatFusion", "pca": "PCAFusion", "cca": "CCAFusion",
           "maxpool": "MaxPoolFusion"}[fusion]
    return np.asarray(getattr(fusion_mod, cls)().fit_transform(views)), None


def _cluster(fused, params, y, trip, n_fixed):
    """(clusters, confidence, n_clusters) in the mode the constraints ask for."""
    from .clustering import SelfTuningSpectralClustering, TripletClustering
    rs = params.random_state
    if y is not None:
        n_cls = int(y.max()) + 1
        # Labels act twice: eq. 2 ties the labelled shapes' fused features to class bases (in
        # every round), and the classes are then spread over a k-NN graph of those features, so
        # the unlabelled shapes' own structure decides their class. PSLF's own transduction
        # (least squares on the class bases) uses the labelled shapes only: on the sample it
        # reached 0.933 purity with 20% labels, label spreading 0.956 (voxel subset: 0.550 vs
        # 0.561), bench/evaluate.py --only "labels 20".
        from sklearn.semi_supervised import LabelSpreading
        ls = LabelSpreading(kernel="knn", n_neighbors=min(7, len(fused) - 1)).fit(fused, y)
        clusters = np.asarray(ls.transduction_, np.int64)
        full = np.zeros((len(fused), n_cls))
        full[:, ls.classes_[ls.classes_ >= 0]] = ls.label_distributions_
        clusters[y >= 0] = y[y >= 0]                       # a given label is never overruled
        conf = full[np.arange(len(fused)), clusters] / np.maximum(full.sum(axis=1), 1e-12)
        conf[y >= 0] = 1.0
        return clusters, np.clip(conf, 0, 1), n_cls
    if trip is not None:
        n_c = n_fixed
        if n_c is None:
            auto = SelfTuningSpectralClustering(n_clusters=None, random_state=rs)
            auto.fit_predict(fused)
            n_c = int(auto.n_clusters_)
        model_t = TripletClustering(n_clusters=n_c, random_state=rs)
        raw = np.asarray(model_t.fit_predict(fused, trip))
        memb = np.asarray(model_t.membership_, np.float64)
        conf = memb[np.arange(len(raw)), raw] / np.maximum(memb.sum(axis=1), 1e-12)
        clusters = _relabel_by_appearance(raw)
        return clusters, np.clip(conf, 0, 1), int(len(np.unique(clusters)))
    model_u = SelfTuningSpectralClustering(n_clusters=n_fixed, random_state=rs)
    clusters = _relabel_by_appearance(np.asarray(model_u.fit_predict(fused)))
    return clusters, _soft_confidence(fused, clusters), int(len(np.unique(clusters)))


def structure_residual(words: np.ndarray, structure: np.ndarray, neighbours: float) -> np.ndarray:
    """Style words minus what the shape's structural neighbours have anyway: (N, K).

    Style, here as in the paper, is what recurs across structurally different shapes. On the
    sample collection the frequency of small-patch words is dominated by category (k-means k=4:
    0.41 style, 0.71 category purity) although a classifier reads style from it at 0.94. So each
    shape's word profile is compared with the mean profile of its `neighbours` * N nearest shapes
    in a *structure* space (the same encoding with large, layout-scale patches, standardised): a
    word that all shapes of this build have (a bed's long rails) cancels, an ornament word the
    shape has more than its look-alikes stays. No labels: the neighbourhoods come from the
    drawings. Measured (k-means k=4, 3 seeds): centring within k-means groups of the structure
    space gave 0.80-0.89 style, subtracting the 20 nearest neighbours' mean 0.97 (10: 0.84, 5: 0.48
    - too few neighbours share the shape's own style and cancel it), and centring within the true
    categories (oracle) 0.89.
    """
    n = len(words)
    k = int(np.clip(round(neighbours * n), 1, n - 1)) if n > 1 else 0
    if k == 0:
        return words - words.mean(axis=0)
    s = (structure - structure.mean(axis=0)) / (structure.std(axis=0) + 1e-9)
    d2 = ((s[:, None, :] - s[None, :, :]) ** 2).sum(axis=2)
    np.fill_diagonal(d2, np.inf)
    nn = np.argsort(d2, axis=1, kind="stable")[:, :k]
    return words - words[nn].mean(axis=1)


def style_space(residual: np.ndarray, n_dims: int, random_state: int = 0) -> np.ndarray:
    """Standardised residuals -> principal subspace of `n_dims` -> unit rows: (N, d).

    Standardising lets rare ornament words count as much as common ones; the PCA keeps the
    directions along which many words co-vary (a style is a set of ornaments that occur
    together), dropping word-level noise; unit rows make clustering compare directions.
    Measured: k-means on all 200 standardised residual words 0.97, on PCA-10 0.98, PCA-5 0.89."""
    x = np.asarray(residual, np.float64)
    x = (x - x.mean(axis=0)) / (x.std(axis=0) + 1e-9)
    d = int(min(n_dims, x.shape[1], max(len(x) - 1, 1)))
    from sklearn.decomposition import PCA
    p = PCA(d, random_state=random_state).fit_transform(x) if d >= 1 else x
    return p / np.maximum(np.linalg.norm(p, axis=1, keepdims=True), 1e-12)


def _fusion_views(space: np.ndarray, fusion: str) -> list[np.ndarray]:
    """Views handed to the fusion. PSLF is a non-negative factorisation, so the signed style
    space is given as its positive and negative parts (two non-negative views that together hold
    it exactly); the other fusions take the same two blocks."""
    return [np.maximum(space, 0.0), np.maximum(-space, 0.0)]


def choose_n_clusters(x: np.ndarray, random_state: int = 0, max_clusters: int = 10) -> int:
    """Number of clusters with the best silhouette of k-means on `x` (2..max_clusters).

    Why not the self-tuning spectral choice (rotation cost): on the sample's style space it picked
    2 or 10 clusters depending on details (style purity 0.48-0.94); the silhouette picked 4 for
    the settings used here (0.96-0.98)."""
    from sklearn.cluster import KMeans
    from sklearn.metrics import silhouette_score
    n = len(x)
    best, best_s = 1, -np.inf
    for c in range(2, min(max_clusters, n - 1) + 1):
        lab = KMeans(c, n_init=5, random_state=random_state).fit_predict(x)
        if len(np.unique(lab)) < 2:
            continue
        sc = silhouette_score(x, lab)
        if sc > best_s:
            best, best_s = c, sc
    return max(best, 2) if n > 2 else 1


def analyse(drawings: list[ShapeDrawings], params: AnalysisParams,
            labels: dict | None = None, triplets: list | None = None, fusion: str = "pslf",
            progress=None, cancel=None, maps: np.ndarray | None = None) -> AnalysisResult:
    """Cluster shapes by style and find their style filters (unsupervised, labels or triplets).

    `maps`: the drawings' HOG maps (N, V, by, bx, C) when the caller already has them (the job
    reuses them to find style regions); computed here otherwise."""
    if params.method == "paper":
        from .paper_method import analyse_paper
        return analyse_paper(drawings, params, labels, triplets, progress, cancel, maps)
    if params.method != "default":
        raise InputError(f"unknown method '{params.method}', choose 'default' or 'paper'")
    timings: dict[str, float] = {}
    prog = Progress.wrap(progress, cancel)
    names, y, classes, trip = _check_inputs(drawings, params, labels, triplets, fusion)
    n = len(drawings)
    n_views = drawings[0].n_views
    image_size = tuple(drawings[0].images.shape[1:3])

    t = time.perf_counter()
    prog.step("patches", 0, 1)
    patches = extract_patches(drawings, size=params.patch_size)
    if len(patches) == 0:
        raise InputError("no patch with ink in any drawing: the shapes drew no lines")
    timings["patches"] = time.perf_counter() - t

    if maps is None:
        t = time.perf_counter()
        maps = []
        for i, d in enumerate(drawings):
            prog.step("hog", i, n)
            maps.append(hog_images(d.images))
        maps = np.stack(maps)                                 # (N, V, by, bx, C)
        timings["hog"] = time.perf_counter() - t

    t = time.perf_counter()
    prog.step("representatives", 0, 1)
    rs = params.random_state
    bank = shared_bank(maps, patches.shape, patches.view, patches.seed, patches.centre,
                       params.patch_size, params.n_words, rs)
    layout = shared_bank(maps, patches.shape, patches.view, patches.seed, patches.centre,
                         params.structure_patch_size, params.n_representatives, rs + 1)
    timings["representatives"] = time.perf_counter() - t
    if len(bank) == 0:
        raise InputError("no patch with ink in any drawing: the shapes drew no lines")

    t = time.perf_counter()
    prog.step("encode", 0, 2)
    words = frequency_features(word_counts(maps, bank.hog))
    prog.step("encode", 1, 2)
    structure = frequency_features(word_counts(maps, layout.hog))
    residual = structure_residual(words, structure, params.structure_neighbours)
    timings["encode"] = time.perf_counter() - t

    keep = np.ones(len(bank), bool)
    clusters = prev = None
    n_fixed = params.n_clusters
    rounds = []
    seen = set()                                              # states met before: a cycle ends too
    for r in range(max(1, params.max_rounds)):
        t = time.perf_counter()
        prog.step("fuse", r, params.max_rounds)
        used = keep
        space = style_space(residual[:, used], params.n_style_dims, rs)
        fused, weights = _fuse(_fusion_views(space, fusion), params, y, fusion)
        timings["fuse"] = timings.get("fuse", 0.0) + time.perf_counter() - t

        t = time.perf_counter()
        prog.step("cluster", r, params.max_rounds)
        if y is None and n_fixed is None:
            n_fixed = choose_n_clusters(space, rs)            # chosen once, in round 0
        clusters, conf, n_c = _cluster(fused, params, y, trip, n_fixed)
        timings["cluster"] = timings.get("cluster", 0.0) + time.perf_counter() - t

        t = time.perf_counter()
        prog.step("reselect", r, params.max_rounds)
        sel = reselect(residual, clusters, np.zeros(len(bank), np.int64), mu=params.mu,
                       min_per_view=params.min_filters)
        timings["reselect"] = timings.get("reselect", 0.0) + time.perf_counter() - t
        changed = n_changed(prev, clusters)
        same_filters = bool(np.array_equal(sel.keep, keep))
        rounds.append({"round": r, "n_filters": int(keep.sum()), "n_clusters": n_c,
                       "n_changed": changed, "n_selected": int(sel.keep.sum()),
                       "n_passed": sel.n_passed,
                       "clusters": [int(c) for c in clusters]})
        state = (_partition_key(clusters), sel.keep.tobytes())
        if (prev is not None and changed == 0 and same_filters) or state in seen:
            break
        seen.add(state)
        prev, keep = clusters, sel.keep

    t = time.perf_counter()
    prog.step("responses", 0, 1)
    final = np.flatnonzero(sel.keep)
    responses = cross_view_responses(maps, bank.subset(final), image_size)
    timings["responses"] = time.perf_counter() - t

    best = sel.scores.argmax(axis=0) if sel.scores.size else np.zeros(len(bank), np.int64)
    cluster_ids = np.unique(clusters)
    style_filters = [StyleFilter(cluster=int(cluster_ids[best[f]]) if len(cluster_ids) > 1 else
                                 int(cluster_ids[0]),
                                 view=int(bank.view[f]), hog=bank.hog[f],
                                 source_shape=int(bank.shape[f]), source_seed=int(bank.seed[f]),
                                 source_pixel=(float(bank.pixel[f, 0]), float(bank.pixel[f, 1])),
                                 score=float(sel.score[f])) for f in final]
    word_cluster = np.full(len(bank), -1, np.int64)
    word_score = np.full(len(bank), -np.inf)
    for f, sf in zip(final, style_filters):
        word_cluster[f], word_score[f] = sf.cluster, sf.score
    predicted = [classes[c] for c in clusters] if classes is not None else None
    label_given = (y >= 0) if y is not None else np.zeros(n, bool)
    if weights is not None:
        weights = np.asarray(weights)
    n_clusters = len(classes) if classes is not None else int(len(np.unique(clusters)))
    prog.step("done", 1, 1)
    return AnalysisResult(names=names, clusters=np.asarray(clusters, np.int64),
                          n_clusters=n_clusters, fused=np.asarray(fused), confidence=conf,
                          classes=classes, predicted=predicted, label_given=label_given,
                          style_filters=style_filters, responses=responses, view_weights=weights,
                          rounds=rounds, timings=timings, words=bank.hog,
                          word_cluster=word_cluster, word_score=word_score)


def style_similarity(result: AnalysisResult) -> np.ndarray:
    """(N, N) style distance between shapes, from the fused features (clustering.style_distance)."""
    from .clustering import style_distance
    return np.asarray(style_distance(result.fused))
