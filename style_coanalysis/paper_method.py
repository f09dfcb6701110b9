"""The paper's own method (Yu et al., sections 3-4.5 as written), a baseline for `pipeline.analyse`.

`analyse_paper` maps onto the paper step by step:

* 4.1 Patch sampling: the first `N_SEEDS` = 30 seeds of each shape (they come in farthest-point
  order, so the first 30 cover the surface as 30 samples would); a 48x48 patch (sec. 5
  "Parameters") around each seed in every view where the seed is visible
  (`patches.extract_patches`; it also drops windows with under 1 % ink, blank paper).
* 4.1 Pre-selection: per view, k-means over the HOG descriptors of that view's patches,
  `params.n_representatives` (paper: 50) centres (`build_filter_bank`).
* 4.2 Per-view encoding: each view's representatives convolve that view's HOG map (cosine),
  max-pooled over the whole image and its 4 quadrants: 5 values per filter, 5K per view
  (`encode`, `view_features`).
* 4.3 Fusion, eq. 1: PSLF over the P views, K = `params.n_components`, eta, lambda, learned view
  weights pi (`pslf.PSLF`).
* 4.4 Labels, eq. 2: the same PSLF with the label term (beta, gamma); unlabelled shapes by
  V_u = W Y_u, the label of largest probability.
* 4.4 Triplets, eq. 3: A' = A + N_m - N_c factorised as Y S Y^T (`clustering.TripletClustering`).
* 4.4 Unsupervised: self-tuning spectral clustering, the rotation cost choosing k when
  `params.n_clusters` is None (`clustering.SelfTuningSpectralClustering`).
* 4.5 Reselection, eq. 4 as printed (`eq4_reselect`), then re-encode, fuse, cluster again until
  clusters and patches are stable or `params.max_rounds`.

Where the paper is ambiguous, and what is chosen here:

* Patch size: fixed at 48 px (paper), whatever `params.patch_size` says (that field is the
  default method's 24 px).
* "The cluster centers are selected as the representative patches": `build_filter_bank` uses the
  real patch nearest each centre (a medoid) so every filter is a patch one can show.
* Feature scale: the paper feeds X^p to PSLF as is, so `scaling="none"` (the raw cosine
  responses, already in [0, 1]). PSLF's internal choices (unit-norm bases, beta and gamma
  calibrated to the data, its solver) are the class's and are not changed here.
* Label prediction: V_u = W Y_u is solved per unlabelled shape by non-negative least squares in
  the plain Euclidean metric (not PSLF's learned label metric), Y_u normalised to sum 1 and read
  as probabilities; given labels are never overruled.
* Triplets: the paper's A = V^T V is taken on unit-length feature vectors (cosine), so that the
  +-1 must-/cannot-link indicators of eq. 3 are on the scale of a shape's self-similarity (raw
  inner products of PSLF factors have an arbitrary scale); no learned metric (`metric=False`).
  The cluster of a shape is the argmax of its row of Y (the paper's cluster indicator), not
  `TripletClustering.labels_` (which adds hard constraint handling). Kept from the class, as it
  cannot be switched off: must-links are closed transitively before building N_m and N_c, and Y
  starts from a constrained spectral embedding (the paper does not say how Y starts).
* Number of clusters with triplets (not said): `params.n_clusters`, else the self-tuning choice
  on the round's fused features. Unsupervised, k is re-chosen by the self-tuning clustering in
  every round (each clustering is the paper's self-tuning one).
* Eq. 4: x_ij, "shape i supports patch j", is read as: one of shape i's own seed patches in
  patch j's view has j as its nearest representative (cosine in HOG space), i.e. shape i has a
  member of j's k-means cluster. That is the frequent-pattern sense of support and needs no
  response threshold. N_p, "the total number of patches", is the number of candidate
  representatives of all views (V x 50 in the paper); the candidates are the initial
  representatives in every round (re-selected, not pruned further), so a patch dropped after an
  early clustering can return. Weights omega_li = x_li / C - 1/N_p, threshold mu N_p / C and the
  absolute value are as printed; the absolute value also keeps a patch that is markedly *absent*
  from a cluster. Read this way a cluster must have more than about mu N_p members for any
  patch to pass (42 with 600 candidates). When no patch passes at all the current set is kept
  (there is nothing to select with); a view with no patch kept drops out of the fusion (its
  view weight is reported as 0).
* Stopping: the loop ends when the reselected set equals the set just used (the next round
  would reproduce this one exactly: clusters and patches stable), when it returns to a set used
  before (a cycle), or after `params.max_rounds` rounds.

Nothing here reads ground truth.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy.optimize import nnls

from .clustering import SelfTuningSpectralClustering, TripletClustering
from .drawings import ShapeDrawings
from .encoding import EPS, FilterBank, representatives, unit_rows
from .features import PIXELS_PER_CELL, collection_maps, patch_descriptors
from .meshes import InputError
from .params import AnalysisParams
from .patches import Patches, extract_patches
from .pipeline import AnalysisResult, StyleFilter, _check_inputs, _relabel_by_appearance, \
    _soft_confidence, n_changed
from .progress import Progress
from .pslf import PSLF

N_POOL = 5          # whole image + 4 quadrants


def correlate_pooled(maps: np.ndarray, filters: np.ndarray, image_size: tuple[int, int],
                     chunk_values: int = 12_000_000) -> np.ndarray:
    """Cosine responses of every filter over every map, max-pooled: (M, K, 5).

    maps: (M, by, bx, C) HOG block maps; filters: (K, nb, nb, C). Pool order: whole image, then
    quadrants top-left, top-right, bottom-left, bottom-right (by window centre pixel).
    """
    maps = np.asarray(maps, np.float32)
    filters = np.asarray(filters, np.float32)
    m, by, bx, c = maps.shape
    k, nb = len(filters), filters.shape[1]
    oy, ox = by - nb + 1, bx - nb + 1
    out = np.zeros((m, k, N_POOL), np.float32)
    if m == 0 or k == 0 or oy <= 0 or ox <= 0:
        return out
    # sliding_window_view puts the window axes last: (M, oy, ox, C, nb, nb); match the filters
    fmat = unit_rows(filters.transpose(0, 3, 1, 2)).T                                          # (C*nb*nb, K)
    h, w = image_size
    centre = (np.arange(oy) + (nb + 1) / 2) * PIXELS_PER_CELL
    top = centre < h / 2
    centre_x = (np.arange(ox) + (nb + 1) / 2) * PIXELS_PER_CELL
    left = centre_x < w / 2
    quads = [(top, left), (top, ~left), (~top, left), (~top, ~left)]
    step = max(1, chunk_values // (oy * ox * c * nb * nb))
    for s in range(0, m, step):
        win = sliding_window_view(maps[s:s + step], (nb, nb), axis=(1, 2))
        cols = win.reshape(-1, c * nb * nb)                              # copy: (b*oy*ox, D)
        norm = np.sqrt(np.einsum("ij,ij->i", cols, cols))
        resp = (cols @ fmat) / np.maximum(norm, EPS)[:, None]
        resp[norm < EPS] = 0.0
        resp = resp.reshape(-1, oy, ox, k)
        out[s:s + step, :, 0] = resp.max(axis=(1, 2))
        for q, (rows, colsel) in enumerate(quads, start=1):
            if rows.any() and colsel.any():
                out[s:s + step, :, q] = resp[:, rows][:, :, colsel].max(axis=(1, 2))
    return np.clip(out, 0.0, 1.0)




def encode(view_maps: np.ndarray, bank: FilterBank, image_size: tuple[int, int]) -> np.ndarray:
    """Pooled responses of each filter over its own view in every shape: (N, F, 5).

    view_maps: (N, V, by, bx, C). Each view's filters run only on that view of each shape, so
    the per-view feature of view v is `pooled[:, bank.view == v].reshape(N, -1)` (5K values).
    """
    n = view_maps.shape[0]
    out = np.zeros((n, len(bank), N_POOL), np.float32)
    for v in np.unique(bank.view):
        idx = np.flatnonzero(bank.view == v)
        out[:, idx] = correlate_pooled(view_maps[:, v], bank.hog[idx], image_size)
    return out




def view_features(pooled: np.ndarray, bank_view: np.ndarray, keep: np.ndarray | None,
                  n_views: int) -> list[np.ndarray]:
    """Per-view feature matrices (N, 5 K_v) from pooled responses, using only the kept filters.

    Re-encoding with a subset of filters is exactly this column selection, so it costs nothing.
    """
    n = pooled.shape[0]
    keep = np.ones(len(bank_view), bool) if keep is None else np.asarray(keep, bool)
    return [pooled[:, keep & (bank_view == v)].reshape(n, -1) for v in range(n_views)]




def build_filter_bank(view_maps: np.ndarray, shape: np.ndarray, view: np.ndarray,
                      seed: np.ndarray, centre: np.ndarray, size: int, k: int,
                      random_state: int = 0) -> FilterBank:
    """Representative filters of every view from the collection's patches.

    view_maps: (N, V, by, bx, C); shape, view, seed: (n,) per patch; centre: (n, 2) (x, y).
    Descriptors are cut from the maps (features.patch_descriptors), so each filter is exactly
    a window of its source view's map. Windows with no gradient at all are ignored.
    """
    n_shapes, n_views = view_maps.shape[:2]
    shape = np.asarray(shape, np.int64)
    view = np.asarray(view, np.int64)
    flat = view_maps.reshape(n_shapes * n_views, *view_maps.shape[2:])
    desc, _ = patch_descriptors(flat, shape * n_views + view, centre, size)
    nonblank = desc.reshape(len(desc), -1).max(axis=1) > EPS if len(desc) else np.zeros(0, bool)
    picks = []
    for v in range(n_views):
        idx = np.flatnonzero((view == v) & nonblank)
        if len(idx):
            picks.append(idx[representatives(desc[idx], k, random_state + v)])
    pick = np.concatenate(picks) if picks else np.zeros(0, np.int64)
    hogs = unit_rows(desc[pick]).reshape(desc[pick].shape) if len(pick) else desc[:0]
    return FilterBank(hogs.astype(np.float32), view[pick], shape[pick],
                      np.asarray(seed, np.int64)[pick], np.asarray(centre, np.float32)[pick])


N_SEEDS = 30        # seeds per shape (paper 4.1)
PATCH_SIZE = 48     # pixels (paper 5, "Parameters")


@dataclass
class Eq4Selection:
    """Outcome of eq. 4 for one clustering; row l of the (C, F) arrays is cluster `ids[l]`."""

    keep: np.ndarray        # (F,) bool, the union of the K_l
    passed: np.ndarray      # (C, F) bool, j in K_l
    signed: np.ndarray      # (C, F) sum_i omega_li (2 x_ij - 1), before the absolute value
    delta: np.ndarray       # (C, F) delta_lj
    threshold: float        # delta_l^t (the same for every l)
    ids: np.ndarray         # (C,) cluster ids


def eq4_reselect(support: np.ndarray, clusters: np.ndarray, n_patches: int,
                 mu: float) -> Eq4Selection:
    """Eq. 4 as printed: K_l = {j : |sum_i omega_li (2 x_ij - 1)| > mu N_p / C}, K = union K_l.

    support: (N, F) bool x_ij; clusters: (N,) ids; n_patches: N_p; omega_li = x_li / C - 1/N_p.
    """
    x = np.asarray(support, np.float64)
    clusters = np.asarray(clusters)
    ids = np.unique(clusters)
    c = len(ids)
    n_p = max(int(n_patches), 1)
    omega = (clusters[None, :] == ids[:, None]) / c - 1.0 / n_p          # (C, N)
    signed = omega @ (2.0 * x - 1.0)                                       # (C, F)
    delta = np.abs(signed)
    threshold = mu * n_p / c
    passed = delta > threshold
    return Eq4Selection(passed.any(axis=0), passed, signed, delta, float(threshold), ids)


def seed_support(maps: np.ndarray, patches: Patches, bank: FilterBank, n_shapes: int) -> np.ndarray:
    """x_ij of eq. 4: (N, F) bool, shape i has a seed patch whose nearest representative is j.

    Nearest by cosine of HOG descriptors among the representatives of the patch's own view, as in
    the per-view k-means that made them; blank descriptors support nothing.
    """
    n_views = maps.shape[1]
    flat = maps.reshape(-1, *maps.shape[2:])
    x = np.zeros((n_shapes, len(bank)), bool)
    for v in range(n_views):
        pidx = np.flatnonzero(patches.view == v)
        fidx = np.flatnonzero(bank.view == v)
        if len(pidx) == 0 or len(fidx) == 0:
            continue
        shape = patches.shape[pidx].astype(np.int64)
        desc, _ = patch_descriptors(flat, shape * n_views + v, patches.centre[pidx], PATCH_SIZE)
        d = desc.reshape(len(desc), -1)
        ok = d.max(axis=1) > EPS
        if not ok.any():
            continue
        sim = unit_rows(d[ok]) @ unit_rows(bank.hog[fidx]).T
        x[shape[ok], fidx[sim.argmax(axis=1)]] = True
    return x


def _predict_from_bases(fused: np.ndarray, w: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(N, C) label probabilities: V_u = W Y_u by NNLS per unlabelled shape (eq. 2's prediction),
    normalised; labelled shapes one-hot on their given class."""
    n, c = len(fused), w.shape[1]
    dist = np.zeros((n, c))
    for i in range(n):
        if y[i] >= 0:
            dist[i, y[i]] = 1.0
            continue
        coef, _ = nnls(w, fused[i])
        s = coef.sum()
        dist[i] = coef / s if s > 0 else np.full(c, 1.0 / c)
    return dist


def _auto_k(fused: np.ndarray, rs: int) -> tuple[int, dict]:
    """Self-tuning spectral clustering's own choice of k (rotation cost) and its costs."""
    if len(fused) < 3:
        return 1, {}
    model = SelfTuningSpectralClustering(n_clusters=None, random_state=rs).fit(fused)
    return int(model.n_clusters_), {int(k): float(v) for k, v in model.rotation_costs_.items()}


def _cluster(fused, model, params, y, trip):
    """(clusters (N,), confidence (N,), n_clusters, info) in the mode the constraints ask for."""
    rs = params.random_state
    n = len(fused)
    if y is not None:                                    # eq. 2: V_u = W Y_u, largest probability
        dist = _predict_from_bases(fused, np.asarray(model.W_), y)
        clusters = dist.argmax(axis=1)
        clusters[y >= 0] = y[y >= 0]
        conf = dist[np.arange(n), clusters]
        return clusters.astype(np.int64), np.clip(conf, 0, 1), int(model.W_.shape[1]), {}
    info = {}
    if trip is not None:                                 # eq. 3
        k = params.n_clusters
        if k is None:
            k, info["rotation_costs"] = _auto_k(fused, rs)
        tc = TripletClustering(n_clusters=k, random_state=rs, metric=False, similarity="cosine")
        tc.fit(fused, trip)
        memb = np.asarray(tc.membership_, np.float64)
        raw = memb.argmax(axis=1)
        conf = memb[np.arange(n), raw]
        clusters = _relabel_by_appearance(raw)
        return clusters, np.clip(conf, 0, 1), int(len(np.unique(clusters))), info
    if params.n_clusters is None and n < 3:
        clusters = np.zeros(n, np.int64)
    else:
        st = SelfTuningSpectralClustering(n_clusters=params.n_clusters, random_state=rs)
        clusters = _relabel_by_appearance(np.asarray(st.fit_predict(fused)))
        if params.n_clusters is None:
            info["rotation_costs"] = {int(k): float(v) for k, v in st.rotation_costs_.items()}
    conf = _soft_confidence(fused, clusters) if len(np.unique(clusters)) > 1 else np.ones(n)
    return clusters, conf, int(len(np.unique(clusters))), info


def _word_clusters(sel: Eq4Selection, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per kept filter: the cluster whose style it marks and its delta.

    The cluster is the one where the filter passed eq. 4 *and* is frequent (signed score > 0),
    the largest such delta; a filter kept only for being absent from a cluster (or kept because
    nothing passed) marks no cluster (-1) and scores its largest delta.
    """
    marks = sel.passed & (sel.signed > 0)
    masked = np.where(marks, sel.delta, -np.inf)
    best = masked.argmax(axis=0)
    cluster = np.where(marks.any(axis=0), sel.ids[best], -1)
    score = np.where(marks.any(axis=0), sel.delta[best, np.arange(sel.delta.shape[1])],
                     sel.delta.max(axis=0) if sel.delta.size else 0.0)
    idx = np.flatnonzero(keep)
    return cluster[idx].astype(np.int64), score[idx].astype(np.float64)


def analyse_paper(drawings: list[ShapeDrawings], params: AnalysisParams,
                  labels: dict | None = None, triplets: list | None = None, progress=None,
                  cancel=None, maps: np.ndarray | None = None) -> AnalysisResult:
    """Cluster shapes by style with the paper's method (sections 3-4.5), see the module docstring.

    `maps`: the drawings' HOG maps (N, V, by, bx, C), or a sequence of each shape's, if the
    caller has them; computed otherwise. The paper's method holds every map at once (it
    convolves all shapes' view v with view v's filters).
    """
    timings: dict[str, float] = {}
    prog = Progress.wrap(progress, cancel)
    names, y, classes, trip = _check_inputs(drawings, params, labels, triplets, "pslf")
    n = len(drawings)
    if params.n_clusters is not None and params.n_clusters > n and y is None:
        raise InputError(f"asked for {params.n_clusters} clusters but there are only {n} shapes")
    n_views = drawings[0].n_views
    image_size = tuple(drawings[0].images.shape[1:3])
    rs = params.random_state

    t = time.perf_counter()
    prog.step("patches", 0, 1)
    patches = extract_patches(drawings, size=PATCH_SIZE)
    patches = patches.subset(patches.seed < N_SEEDS)
    if len(patches) == 0:
        raise InputError("no patch with ink in any drawing: the shapes drew no lines")
    timings["patches"] = time.perf_counter() - t

    if maps is None:
        t = time.perf_counter()
        maps = collection_maps(drawings, lambda i, total: prog.step("hog", i, total))
        timings["hog"] = time.perf_counter() - t
    maps = np.stack([np.asarray(maps[i], np.float32) for i in range(len(maps))])
    if maps.shape[:2] != (n, n_views):
        raise InputError(f"HOG maps for {maps.shape[:2]} (shapes, views), expected {(n, n_views)}")

    t = time.perf_counter()
    prog.step("representatives", 0, 1)
    bank = build_filter_bank(maps, patches.shape, patches.view, patches.seed, patches.centre,
                             PATCH_SIZE, params.n_representatives, rs)
    if len(bank) == 0:
        raise InputError("no patch with ink in any drawing: the shapes drew no lines")
    support = seed_support(maps, patches, bank, n)
    timings["representatives"] = time.perf_counter() - t

    t = time.perf_counter()
    prog.step("encode", 0, 1)
    pooled = encode(maps, bank, image_size)                    # (N, F, 5)
    timings["encode"] = time.perf_counter() - t

    keep = np.ones(len(bank), bool)
    used = {keep.tobytes()}
    prev = None
    rounds = []
    for r in range(max(1, params.max_rounds)):
        t = time.perf_counter()
        prog.step("fuse", r, params.max_rounds)
        per_view = view_features(pooled, bank.view, keep, n_views)
        active = [v for v in range(n_views) if per_view[v].shape[1] > 0]
        model = PSLF(n_components=params.n_components, eta=params.eta, lam=params.lam,
                     beta=params.beta, gamma=params.gamma, scaling="none", random_state=rs)
        fused = np.asarray(model.fit_transform([per_view[v] for v in active], y=y))
        weights = np.zeros(n_views)
        weights[active] = model.view_weights_
        timings["fuse"] = timings.get("fuse", 0.0) + time.perf_counter() - t

        t = time.perf_counter()
        prog.step("cluster", r, params.max_rounds)
        clusters, conf, n_c, info = _cluster(fused, model, params, y, trip)
        timings["cluster"] = timings.get("cluster", 0.0) + time.perf_counter() - t

        t = time.perf_counter()
        prog.step("reselect", r, params.max_rounds)
        sel = eq4_reselect(support, clusters, len(bank), params.mu)
        n_passed = int(sel.keep.sum())
        new_keep = sel.keep if n_passed else keep             # nothing passed: nothing to select
        timings["reselect"] = timings.get("reselect", 0.0) + time.perf_counter() - t

        rounds.append({"round": r, "n_filters": int(keep.sum()), "n_clusters": n_c,
                       "n_changed": n_changed(prev, clusters), "n_selected": int(new_keep.sum()),
                       "n_passed": n_passed, "threshold": sel.threshold,
                       "views_used": [int(v) for v in active],
                       "clusters": [int(c) for c in clusters], **info})
        prev = clusters
        if np.array_equal(new_keep, keep) or new_keep.tobytes() in used:
            keep = new_keep
            break
        used.add(new_keep.tobytes())
        keep = new_keep

    final = np.flatnonzero(keep)
    kept = bank.subset(final)

    word_cluster, word_score = _word_clusters(sel, keep)
    style_filters = [StyleFilter(cluster=int(word_cluster[k]), view=int(kept.view[k]),
                                 hog=kept.hog[k], source_shape=int(kept.shape[k]),
                                 source_seed=int(kept.seed[k]),
                                 source_pixel=(float(kept.pixel[k, 0]), float(kept.pixel[k, 1])),
                                 score=float(word_score[k])) for k in range(len(kept))]
    predicted = [classes[c] for c in clusters] if classes is not None else None
    label_given = (y >= 0) if y is not None else np.zeros(n, bool)
    n_clusters = len(classes) if classes is not None else int(len(np.unique(clusters)))
    prog.step("done", 1, 1)
    return AnalysisResult(names=names, clusters=np.asarray(clusters, np.int64),
                          n_clusters=n_clusters, fused=fused, confidence=np.asarray(conf),
                          classes=classes, predicted=predicted, label_given=label_given,
                          style_filters=style_filters, view_weights=weights,
                          view_names=[f"view {v}" for v in range(len(weights))]
                          if weights is not None else [],
                          rounds=rounds, timings=timings, words=kept.hog,
                          word_cluster=word_cluster, word_score=word_score)
