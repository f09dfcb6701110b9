"""The whole analysis in one call (paper 4.1-4.5): drawings in, style clusters and style words out.

    HOG maps -> counts of several synthetic dictionaries of style words (24, 16, 32 px; each for
    all views) -> per shape and dictionary: word profile, layout profile (48 px words); line
    character
    -> [views (views.word_views, line character) -> style graph (graph.py; after the first
        round, averaged with the first round's) -> clusters
        -> reselect each dictionary's words]*

`params.method == "paper"` runs the paper's own method instead (paper_method.py), the baseline
every figure of the default is compared with.

Why not the paper's pipeline as written: on the sample it clustered by category (style purity
0.25, category 0.80), and on real furniture and the voxel set it scored below trivial line
statistics (README, "where it departs from the paper"). The default keeps its stages (HOG,
representative patches, encoding, fusion of several views, clustering, reselection until
stable) but each stage is made to hold on collections it was not tuned on:
* dictionaries of small patches for all views, counted over all views (shapes are upright but
  not azimuth-aligned; ornament is small at 200 px), drawn from synthetic line drawings rather
  than the collection (vocabulary.py), so a shape's profile depends on its own drawings only (a
  dictionary drawn from the collection changed every shape's words when a 1e-7 change of
  coordinates redrew a few pixels of a few shapes, and where the cut is ambiguous moved it:
  issue 11, README); several, of their own seeds (`params.n_dictionaries`) and at more than
  one patch size (`params.dictionary_patch_size`, since no one size held on every collection:
  encoding.py), and every one's views enter the style graph;
* the views are the word profile relative to structural look-alikes at every scale of a ladder,
  plus the line character (views.py), fused as graphs (graph.py): no neighbour count or
  collection fraction is chosen for the collection at hand;
* the number of clusters comes from the fused graph's spectral gap, at most N/4 and 10;
* labels: with three or more of every style, they start the graph's cut from the labelled
  shapes (seeded k-means), or, where cross-validation on the labels says it predicts
  held-out labels better, decide which features matter first (a classifier fitted to the
  labelled shapes); with fewer, the graph's own cut named by them is kept unless the seeded
  cut places at least two more labelled shapes in their style (`_label_transduction`);
  triplets constrain the graph's clustering (eq. 3), whose spectral start is the style graph
  itself with the constraints imposed (a 7-nearest graph rebuilt on its spectral coordinates
  moved with the load route: docs/generalisation.md);
* reselection keeps the words that discriminate the clusters; the next round's graph is the
  mean of the first round's (every word) and the graph of the kept words' views. Replacing the
  graph by the kept words' let a few shapes moved by redrawn pixels move the words kept, and
  those the next cut, round after round (collection2 read back from OBJ, automatic k: ARI
  0.97 after the first round, 0.90 after five); kept beside the all-words graph, each round
  moves the graph half as far (docs/generalisation.md: the worst ARI over the three routes,
  3 collections x 3 seeds x 2 modes, 0.92 -> 0.97 on average). The loop stops when neither
  clusters nor words change, on a repeated state, or after `params.max_rounds`.
Every order-dependent step runs in a canonical order, so the file order does not change the
result. Nothing here reads ground truth. Nothing holds every shape's HOG maps or an N x N array
but the triplet mode: `encode` reads the shapes one at a time, the look-alike means are taken in
row blocks, and the graphs are sparse (graph.py), so memory grows linearly with the collection;
the triplet clustering (`clustering.TripletClustering`, eq. 3) factorises a dense N x N
similarity.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment
from sklearn.cluster import KMeans
from sklearn.preprocessing import normalize
from threadpoolctl import threadpool_limits

from . import graph, vocabulary
from .constraints import labels_to_array, triplets_to_array, validate_labels, validate_triplets
from .drawings import ShapeDrawings
from .encoding import FilterBank, frequency_features, shape_word_counts
from .features import PIXELS_PER_CELL, MapStore, hog_images, line_character
from .hashing import uniform
from .meshes import InputError
from .metrics import ari
from .params import AnalysisParams
from .progress import Progress
from .reselection import reselect
from .views import look_alikes, neighbour_ladder, structure_relative, style_space, word_views

FUSIONS = ("graph", "pslf", "concat", "pca", "cca")
# labelled shapes the seeded cut must place in their class beyond the graph's own cut to
# replace it, where some style has fewer than three labels (`_label_transduction`)
SEEDED_MARGIN = 2
# folds that choose the labels' reading, at most (`_label_folds`)
LABEL_FOLDS = 10


@dataclass
class StyleFilter:
    """A kept word and the style it marks, shown by a window of the collection (source shape,
    view, pixel; the paper's filters are that patch, cut at `source_seed`; the default's words
    are synthetic, shown by the window most like them, source_seed -1)."""

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
    view_weights: np.ndarray | None  # weight of each fused view (view_names), when it has one
    view_names: list[str] = field(default_factory=list)
    rounds: list[dict] = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    words: np.ndarray | None = None          # (K, nb, nb, C) the whole dictionary (unit HOG)
    word_cluster: np.ndarray | None = None   # (K,) the cluster a word is a style filter of, or -1
    word_score: np.ndarray | None = None     # (K,) its discriminant score (-inf for other words)
    # automatic k only: the spectral gap of every number of clusters allowed; the largest chose
    k_gaps: dict[int, float] | None = None
    # without labels or triplets: how firmly the drawings hold the clusters (_dictionary_agreement)
    dictionary_agreement: float | None = None


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


def _one_to_one(a: np.ndarray, b: np.ndarray, n_a: int, n_b: int):
    """The one-to-one naming of a's clusters (0..n_a-1) by b's (0..n_b-1) that agrees on the
    most items (Hungarian assignment on their contingency table): (a's clusters, their names
    in b, items agreeing)."""
    table = np.zeros((n_a, n_b), np.int64)
    np.add.at(table, (a, b), 1)
    r, c = linear_sum_assignment(-table)
    return r, c, int(table[r, c].sum())


def n_changed(old: np.ndarray | None, new: np.ndarray) -> int:
    """Shapes whose cluster changed, after the best one-to-one renaming of clusters."""
    if old is None:
        return int(len(new))
    a, b = np.unique(old, return_inverse=True)[1], np.unique(new, return_inverse=True)[1]
    return int(len(new) - _one_to_one(a, b, a.max() + 1, b.max() + 1)[2])


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


def _graphs(views, choice: bool = False) -> tuple[list, list | None]:
    """The graph of each view (`graph.ladder_affinities`) and, with `choice`, its graph at
    `graph.CHOICE_EDGES` nearest that the automatic k reads, from the same nearest-shape search
    (None without); a view that recurs (the line character, once per dictionary) is computed
    once."""
    made = {}
    for v in views:
        if id(v) not in made:
            made[id(v)] = graph.ladder_affinities(v, [graph.CHOICE_EDGES] if choice else [])
    return [made[id(v)][0] for v in views], \
        [made[id(v)][1][0] for v in views] if choice else None


def _style_graph(views, params, y, fusion, choice: bool = False):
    """The fused style graph (N, N), the weight of each view in it, and, with `choice`, the
    graph the automatic k reads (`_cluster_count_gaps`; None without).

    fusion "graph" (default): the mean of the views' graphs. The other fusions fuse the views'
    features first and build one graph of the result, for comparison: "pslf" (paper 4.3, its
    learned view weights; the views shifted to be non-negative), "concat", "pca", "cca"; the
    automatic k reads that graph."""
    if fusion == "graph":
        graphs, choice_graphs = _graphs(views, choice)
        weights = np.full(len(views), 1.0 / len(views))
        return graph.fuse(graphs, weights), weights, \
            graph.fuse(choice_graphs) if choice else None
    shifted = [v - v.min(axis=0) for v in views]
    if fusion == "pslf":
        from .pslf import PSLF
        model = PSLF(n_components=params.n_components, eta=params.eta, lam=params.lam,
                     beta=params.beta, gamma=params.gamma, random_state=params.random_state,
                     scaling="none")
        fused = graph.affinity(model.fit_transform(shifted, y=y))
        return fused, np.asarray(model.view_weights_), fused if choice else None
    from . import fusion as fusion_mod
    cls = {"concat": "ConcatFusion", "pca": "PCAFusion", "cca": "CCAFusion"}[fusion]
    fused = graph.affinity(np.asarray(getattr(fusion_mod, cls)().fit_transform(shifted)))
    return fused, None, fused if choice else None


def _label_transduction(a: np.ndarray, features: np.ndarray, y: np.ndarray, n_classes: int,
                        random_state: int = 0, reading: str | None = None,
                        prog: Progress | None = None):
    """Classes (N,), their distributions (N, C) and the reading of the labels used ("own",
    "seeded" or "metric", below) from the given labels and the style graph. `reading`: use
    that reading rather than choose one; the analysis chooses in its first round and keeps the
    choice, as it keeps the automatic k (a choice made again each round flipped between
    readings as the graph moved, and with it the result: sample-120, 20% labels, read back
    from .blend: ARI 0.83 against the original drawings).

    With too few labels to hold one out (a style with fewer than three), the graph's own cut
    (`graph.partition`, the unsupervised result's) with its clusters named by the labels
    (`_named_cut`) competes with `_seeded_cut` (k-means in the graph's spectral coordinates
    started from the labelled shapes' class means): the seeded cut wins only where it places at
    least `SEEDED_MARGIN` (two) more labelled shapes in their class. So labels the unsupervised
    result already honours change nothing but the names, labels that contradict it move the
    centres, and one label it misplaces is not enough evidence: with one label a style the
    seeded cut starts from single shapes, and placing one label more was noise (a throwaway
    screen on the benchmark's encodings, 34 collections, seeds 0-2, against a margin of one:
    label rows below k given by more than 0.005, 12 -> 6, sample-24 10% labels 0.69 -> 0.81,
    sample-cats-1 0.85 -> 0.90; sample-styles-4 2 labels 0.87 -> 0.81; sums 2 labels 26.80 ->
    26.72, 10% 26.27 -> 26.33, 20% 27.76 -> 27.76; a margin of three lost more on
    sample-styles-4, 0.66; the benchmark on the same drawings, generalisation_s48lab against
    _s48fresh: label rows below k given 13 -> 7, docs/generalisation.md).
    Measured before, against the seeded cut alone (generalisation benchmark, 17 collections, 3
    seeds; generalisation_s17lab): competing with the graph's own cut, 2 labels per style at or
    above the unsupervised result (k given) on 17 of 17 collections (12 before), sum of mean
    purities 12.69 -> 12.91.

    With three or more labels of every style, two readings compete, both seeded cuts:
    * the style graph itself: the labels place the centres and name the clusters;
    * the labels decide what matters (`_label_metric_graph`): a logistic regression fitted to
      the labelled shapes' style features weighs the features that separate the labelled
      styles; its graph, averaged with the unsupervised graph, is cut the same way.
    The second is used when cross-validation on the given labels (hide a fold, predict it from
    the others: `_label_folds`, leave-one-out up to ten labels) says it predicts held-out
    labels better than the first. The graph's own cut named by the labels was below both
    there (10% and 20% labels: collection2 20% 0.83 -> 0.72). The given labels are then
    kept. Only the given labels are read. Each fold refits the regression and cuts a graph,
    so it is reported to `prog` as stage "read labels", which is also where a cancel stops
    it.

    Measured before the graph's own cut competed (generalisation benchmark, 17 collections, 3
    seeds; generalisation_x -> _le): the seeded cut rather than the graph's own cut named
    afterwards raised the sum of the mean style purities 12.35 -> 12.49 with 2 labels per
    style, 12.24 -> 12.33 with 10%, 12.99 -> 13.19 with 20%. Earlier: the discriminant chosen
    on ties, or with fewer labels, lost up to 0.07 (sample-cats-2) where it helped elsewhere;
    spreading the labels over the graph (sklearn's LabelSpreading) was below the named
    partition on most collections."""
    lab = np.flatnonzero(y >= 0)
    # the graph's own spectral coordinates: only choosing a reading and the seeded cut read them
    coords = _unit_coordinates(a, n_classes) if reading in (None, "seeded") else None

    def by_metric(yy):
        g = _label_metric_graph(a, features, yy)
        return _seeded_cut(_unit_coordinates(g, n_classes), yy, n_classes), g

    if reading is None:
        if np.bincount(y[lab], minlength=n_classes).min() >= 3:    # one to hide, two to fit
            right = {"metric": 0, "seeded": 0}
            folds = _label_folds(features[lab], y[lab], n_classes)
            for j, hide in enumerate(folds):
                if prog is not None:
                    prog.step("read labels", j, len(folds))
                hid = lab[hide]
                yy = y.copy()
                yy[hid] = -1
                right["metric"] += int((by_metric(yy)[0][hid] == y[hid]).sum())
                right["seeded"] += int((_seeded_cut(coords, yy, n_classes)[hid] == y[hid]).sum())
            reading = "metric" if right["metric"] > right["seeded"] else "seeded"
        else:
            cuts = {"own": _named_cut(a, y, n_classes, random_state),
                    "seeded": _seeded_cut(coords, y, n_classes)}
            right = {k: int((c[lab] == y[lab]).sum()) for k, c in cuts.items()}
            reading = "seeded" if right["seeded"] >= right["own"] + SEEDED_MARGIN else "own"
            return _with_labels(cuts[reading], a, y, lab, n_classes, reading)
    if reading == "metric":
        clusters, g = by_metric(y)
    elif reading == "own":
        clusters, g = _named_cut(a, y, n_classes, random_state), a
    else:
        clusters, g = _seeded_cut(coords, y, n_classes), a
    return _with_labels(clusters, g, y, lab, n_classes, reading)


def _label_folds(features: np.ndarray, y: np.ndarray, n_classes: int) -> list[np.ndarray]:
    """The labelled shapes (rows of `features`, styles `y`) split into the folds that choose
    the labels' reading: one shape a fold up to `LABEL_FOLDS` labels (leave-one-out), else
    up to `LABEL_FOLDS` folds, each style's shapes dealt round them in a canonical order of
    their features (so the folds follow the shapes, not the file order); folds beyond the
    largest style's number of labels hide nothing and are left out. A fold hides one of every
    ten of a style's labels, rounded up: with three or more of every style, two or more are
    left to fit. Ten folds rather than one a labelled shape: the reading refits a classifier
    and cuts a graph per fold, which grew as (labelled shapes) x N (600 folds, 2.5 min at
    3,000 shapes with 20% labels); on the benchmark's encodings (34 collections, seeds 0-2)
    ten folds chose as well: 10% labels 26.33 -> 26.33, 20% 27.76 -> 27.78
    (docs/generalisation.md)."""
    n = len(y)
    if n <= LABEL_FOLDS:
        return [np.array([i]) for i in range(n)]
    fold = np.empty(n, np.int64)
    order = graph.canonical_order(features)
    for c in range(n_classes):
        members = order[y[order] == c]
        fold[members] = np.arange(len(members)) % LABEL_FOLDS
    folds = [np.flatnonzero(fold == f) for f in range(LABEL_FOLDS)]
    return [f for f in folds if len(f)]


def _with_labels(clusters, g, y, lab, n_classes: int, reading: str):
    """`_label_transduction`'s answer: the classes with the given labels kept, each shape's
    class distribution (its affinity in `g` to the members of each class), the reading."""
    clusters = clusters.copy()
    clusters[lab] = y[lab]
    onehot = np.eye(n_classes)[clusters]
    dist = g @ onehot + 1e-12
    return clusters.astype(np.int64), dist / dist.sum(axis=1, keepdims=True), reading


def _named_cut(a, y: np.ndarray, n_classes: int, random_state: int = 0) -> np.ndarray:
    """Classes (N,): the graph's own spectral cut into n_classes (`graph.partition`), each
    cluster named by the one-to-one naming that puts the most labelled shapes (y >= 0) in
    their class; among namings that place as many, the one whose clusters are most tied in the
    graph to the labelled shapes of their class. Without that tie-break the naming among
    equals followed the cut's arbitrary cluster ids, which a 1e-7 change of coordinates could
    permute: the same cut, named otherwise, put the labelled shapes in other clusters
    (collection2 read back from OBJ, 2 labels per style: ARI 0.90 after the first round)."""
    raw = graph.partition(a, n_classes, random_state)
    lab = np.flatnonzero(y >= 0)
    count = np.zeros((n_classes, n_classes))
    np.add.at(count, (raw[lab], y[lab]), 1.0)
    members, labelled = np.eye(n_classes)[raw], np.eye(n_classes)[y[lab]]
    tie = members.T @ np.asarray(a[:, lab].todense() if hasattr(a, "todense") else a[:, lab]) \
        @ labelled
    tie /= np.maximum(np.outer(members.sum(axis=0), labelled.sum(axis=0)), 1.0)
    # the ties' share is below one placement over the whole naming
    r, c = linear_sum_assignment(-(count + 0.5 * tie / (n_classes * max(tie.max(), 1e-12))))
    name = np.empty(n_classes, np.int64)
    name[r] = c
    return name[raw]


def _unit_coordinates(a, n: int) -> np.ndarray:
    """The graph's top n eigenvectors, rows scaled to unit length: where its spectral cut
    (`graph.partition`) runs k-means."""
    _, u = graph.embedding(a, n)
    return normalize(u)


def _seeded_cut(coords: np.ndarray, y: np.ndarray, n_classes: int) -> np.ndarray:
    """Classes (N,): k-means in the spectral coordinates started from the labelled shapes'
    class means (seeded k-means, Basu et al. 2002), so cluster c is class c by construction
    and the labelled shapes place the centres. Deterministic: one run from given starts."""
    centres = np.stack([coords[y == c].mean(axis=0) for c in range(n_classes)])
    return KMeans(n_classes, init=centres, n_init=1).fit_predict(coords).astype(np.int64)


def _label_metric_graph(a: np.ndarray, features: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The unsupervised graph averaged with the graph of the class probabilities of a logistic
    regression fitted to the labelled shapes (y >= 0) on every dictionary's words and the line
    character: the labels weigh the features.

    Against the shrinkage linear discriminant on the first dictionary's words it replaced
    (a throwaway screen on the benchmark's encodings, 34 collections, seeds 0-2): sums of
    mean style purity with 20% labels 27.42 -> 27.64 (10 collections up, collection2-styles-2
    0.715 -> 0.792, hu2017-styles-2-1 0.667 -> 0.744; 2 down, sample-unbalanced 0.861 -> 0.819,
    hu2017-styles-2-2 0.883 -> 0.839), 10% 26.23 -> 26.22; 2 labels per style do not read it.
    The discriminant's shrinkage estimate of a 1,000-feature covariance made leave-one-out
    20x slower; the regression's fit is not."""
    from sklearn.linear_model import LogisticRegression
    lab = y >= 0
    model = LogisticRegression(C=0.1, max_iter=2000).fit(features[lab], y[lab])
    return 0.5 * (a + graph.affinity(model.predict_proba(features)))


def _cluster(a, features, params, y, trip, n_clusters, reading=None, prog=None):
    """(clusters, confidence, n_clusters, spectral coordinates, reading of the labels) in the
    mode the constraints ask for, from the fused style graph `a` (and, with labels, the
    shapes' style features). `reading`: the labels' reading to use (`_label_transduction`;
    None: choose one, and return it; None without labels). Only the triplet clustering
    returns the coordinates every round (its estimator takes them as its samples; its start
    and similarity come from `a`); the other modes return None for them, and the
    unsupervised cut None for its confidence: both come from the last round's coordinates
    (`_soft_confidence`), which only that round needs. `prog`: where the labels'
    cross-validation reports its folds (and a cancel stops it).

    The labels' readings run on one thread, as the graph's cuts do (`graph.kmeans`): their
    fits are small (k-means on N x k coordinates, a regression on the labelled shapes refitted
    for each fold), and on more threads the BLAS and OpenMP pools wait on each other (3,000
    shapes, 10% labels, when a fold was one label: 72 s of rounds on one thread, 135 s on two,
    269 s on four; the same partitions; docs/generalisation.md, "The cuts on one thread").
    The graphs' searches and the triplet clustering, whose N x N products gain from threads
    at a few thousand shapes, run on every core."""
    rs = params.random_state
    if y is not None:
        n_cls = int(y.max()) + 1
        with threadpool_limits(limits=1):
            clusters, dist, reading = _label_transduction(a, features, y, n_cls, rs, reading,
                                                          prog)
        conf = dist[np.arange(a.shape[0]), clusters] / np.maximum(dist.sum(axis=1), 1e-12)
        conf[y >= 0] = 1.0
        return clusters, np.clip(conf, 0, 1), n_cls, None, reading
    if trip is not None:
        from .clustering import TripletClustering
        # given the style graph it reads no feature metric: none is learned
        model_t = TripletClustering(n_clusters=n_clusters, random_state=rs, metric=False)
        coords = _coordinates(a, params)
        raw = np.asarray(model_t.fit_predict(coords, trip, affinity=a))
        memb = np.asarray(model_t.membership_, np.float64)
        conf = memb[np.arange(len(raw)), raw] / np.maximum(memb.sum(axis=1), 1e-12)
        clusters = _relabel_by_appearance(raw)
        return clusters, np.clip(conf, 0, 1), int(len(np.unique(clusters))), coords, None
    clusters = _relabel_by_appearance(graph.partition(a, n_clusters, rs))
    return clusters, None, int(len(np.unique(clusters))), None, None


def _coordinates(a: np.ndarray, params: AnalysisParams) -> np.ndarray:
    """The shapes' spectral coordinates in the style graph (N, d): what the style distance,
    triplet clustering and the report's map use."""
    _, u = graph.embedding(a, params.n_style_dims + 1)
    return u[:, 1:]


def _views(dicts, keeps, lines, n_dims):
    """Every dictionary's word views (views.word_views, its kept words only), their names (one per
    kind: the ladder's rungs, then line character) and each view's kind. The line-character
    view is the same for every dictionary and is computed once, but counted once per
    dictionary, so its share of the fused graph does not change with their number."""
    views, kinds, names = [], [], []
    for d, keep in zip(dicts, keeps):
        v, names = word_views(d.rungs, keep, n_dims)
        views += v
        kinds += range(len(v))
    line_view = style_space(lines, n_dims)
    views += [line_view] * len(dicts)
    kinds += [len(names)] * len(dicts)
    return views, names + ["line character"], np.asarray(kinds)


def _cluster_count_gaps(a, n: int) -> dict[int, float]:
    """The spectral gap of each number of clusters allowed (graph.spectral_gaps) in `a`: the
    views' graphs at `graph.CHOICE_EDGES` nearest, fused (the default fusion; other fusions:
    their own graph). A sparser graph splits its spectrum into more near-equal gaps: on the
    generalisation benchmark (17 collections, 3 seeds) the gap of the 20-edge style graph was
    right on 17 of 51 runs, of a 40-edge one on 24, of the dense graph on 25. Since the style
    graph is the ladder of 5-40 nearest: 40 nearest 27 of 51, the ladder itself 15."""
    return graph.spectral_gaps(a, _max_clusters(n))


def _dictionary_agreement(dicts, lines, params, clusters, n_clusters: int) -> float | None:
    """How firmly the drawings hold an unsupervised result: the mean ARI between `clusters` and
    each dictionary's own cut into as many clusters (its every word's views and the line
    character, fused as the style graph is). Where the cut is one of several the data support
    about equally, dictionaries of other seeds and patch sizes cut differently; that is also
    where another analysis seed regroups shapes (a re-exported file too, but the agreement does
    not foretell which: docs/generalisation.md). On the generalisation benchmark (36
    collections, 3 seeds, k given) 18 of the 29 runs at 0.8 or more were at least 0.9 pure in
    style, 18 of the 79 below (README, "The report"; report.FIRM). None with one dictionary or
    one cluster."""
    if len(dicts) < 2 or n_clusters < 2:
        return None
    cuts = []
    for d in dicts:
        views, _, _ = _views([d], [np.ones(len(d.bank), bool)], lines, params.n_style_dims)
        cuts.append(graph.partition(graph.fuse(_graphs(views)[0]), n_clusters,
                                    params.random_state))
    return float(np.mean([ari(c, clusters) for c in cuts]))


def _max_clusters(n: int) -> int:
    """Automatic k never exceeds N/4 (a style is something several shapes share) nor 10."""
    return int(max(2, min(10, n // 4)))


@dataclass
class Dictionary:
    """One drawn dictionary of style words and what the clustering rounds read through it."""

    bank: FilterBank             # the style words (params.dictionary_patch_size px patches)
    rungs: list                  # (N, K) per rung of the ladder: word profile relative to look-alikes
    relative: np.ndarray         # (N, K) their mean over the ladder


@dataclass
class Encoding:
    """A collection's encoding (`encode`): what the clustering rounds read. It depends on the
    drawings and the dictionary parameters only, so one encoding serves every mode.
    `dictionaries[0]` is drawn with the analysis seed itself; its words are the ones the result
    reports and marks on the meshes."""

    dictionaries: list[Dictionary]
    lines: np.ndarray            # (N, L) line character
    timings: dict = field(default_factory=dict)


def dictionary_state(random_state: int, member: int) -> int:
    """The seed of the `member`-th dictionary drawn for an analysis seed (the first: the seed)."""
    if member == 0:
        return int(random_state)
    return int(uniform(int(random_state) & 0xFFFFFFFF, member) * 2 ** 31)


def vocabulary_specs(params: AnalysisParams) -> list[tuple[int, int, int]]:
    """(patch size, words, seed) of each synthetic vocabulary `encode` reads, in order: each
    dictionary's style words, then its layout words."""
    return [spec for m in range(params.n_dictionaries)
            for rs in (dictionary_state(params.random_state, m),)
            for spec in ((params.dictionary_patch_size(m), params.n_words, rs),
                         (params.structure_patch_size, params.n_representatives, rs + 1))]


def encode(drawings, params: AnalysisParams, maps=None, progress=None,
           cache_dir=None) -> Encoding:
    """HOG maps -> word, layout and line profiles of every shape.

    `params.n_dictionaries` dictionaries, each a pair of synthetic vocabularies
    (`vocabulary.words`, drawn with the dictionary's seed): style words at its patch size
    (`params.dictionary_patch_size`: 24, 16, 32, 24, 16 px) and layout words (48 px). Nothing
    in them comes from the collection, so a shape's profiles depend on its own drawings only.
    One pass over the shapes, one at a time, so memory does not grow with the HOG maps: each
    shape's maps (kept in a temporary `MapStore` unless `maps`, a sequence of per-shape maps, is
    given), its line character and its word counts. The first dictionary's words are shown
    through the collection's window most like each (`FilterBank`: shape, view, pixel).
    `drawings` may be any sequence of ShapeDrawings, read in order, one at a time; `cache_dir`:
    where the vocabularies are kept (`vocabulary.words`)."""
    prog = Progress.wrap(progress)
    n = len(drawings)
    if params.n_dictionaries < 1:
        raise InputError(f"need at least one dictionary, got n_dictionaries={params.n_dictionaries}")
    sizes = [params.dictionary_patch_size(m) for m in range(params.n_dictionaries)]
    t = time.perf_counter()
    # style and layout words of each dictionary: the default seed's shipped with the package,
    # others some seconds each the first time, then read from the cache: one step each, so a
    # first run shows progress and can be cancelled here
    specs = vocabulary_specs(params)
    made = []
    for j, spec in enumerate(specs):
        prog.step("representatives", j, len(specs))
        made.append(vocabulary.words(*spec, cache_dir))
    banks = list(zip(made[0::2], made[1::2]))
    timings = {"representatives": time.perf_counter() - t, "hog": 0.0, "encode": 0.0}
    counts = [(np.zeros((n, len(b))), np.zeros((n, len(lb)))) for b, lb in banks]
    # the dictionaries of one patch size are matched together (their windows cut once)
    groups = [[j for j, s in enumerate(sizes) if s == size] for size in dict.fromkeys(sizes)]
    k0 = len(banks[0][0])
    near = (np.full(k0, -np.inf), *(np.zeros(k0, np.int64) for _ in range(4)))
    store = MapStore() if maps is None else None
    source = store if store is not None else maps       # where each shape's maps are read
    lines, inked = [], False
    try:
        for i, d in enumerate(drawings):
            t = time.perf_counter()
            if store is not None:
                prog.step("hog", i, n)
                store.append(hog_images(d.images))
            m = source[i]
            timings["hog"] += time.perf_counter() - t
            prog.step("encode", i, n)
            t = time.perf_counter()
            lines.append(line_character(m))
            inked = inked or bool(np.asarray(m).max() > 0)
            for group in groups:
                words_i, best_i = shape_word_counts(m, [banks[j][0] for j in group], best=True)
                for j, w in zip(group, words_i):
                    counts[j][0][i] = w.sum(axis=0)
                if group[0] == 0:                   # the shown dictionary: its best windows
                    cos, view, row, col = best_i[0]
                    better = cos > near[0]
                    for arr, val in zip(near, (cos, np.full(k0, i), view, row, col)):
                        arr[better] = val[better]
            layout_i = shape_word_counts(m, [lb for _, lb in banks])
            for (_, lc), lw in zip(counts, layout_i):
                lc[i] = lw.sum(axis=0)
            timings["encode"] += time.perf_counter() - t
    finally:
        if store is not None:
            store.close()
    if not inked:
        raise InputError("no patch with ink in any drawing: the shapes drew no lines")
    # what reselection scores a word by: how much more of it a shape has than its look-alikes,
    # averaged over the ladder's scales
    t = time.perf_counter()
    ks = neighbour_ladder(n)
    k_far = max([k for k in ks if k < n - 1], default=0)
    dictionaries = []
    for j, ((words, _), (c, lc)) in enumerate(zip(banks, counts)):
        shown = _shown_bank(words, near, sizes[0]) if j == 0 else _shown_bank(words)
        rungs = structure_relative(frequency_features(c[:, None]),
                                   look_alikes(frequency_features(lc[:, None]), k_far), ks)
        dictionaries.append(Dictionary(shown, rungs, np.mean(rungs, axis=0)))
    timings["encode"] += time.perf_counter() - t
    return Encoding(dictionaries, np.stack(lines), timings)


def _shown_bank(words: np.ndarray, near=None, size: int = 0) -> FilterBank:
    """The words as a FilterBank; with `near` (best cosine, shape, view, block row, block column
    per word), each word's shape, view and pixel are the collection's window most like it."""
    k = len(words)
    if near is None:
        z = np.full(k, -1, np.int64)
        return FilterBank(words, z, z, z, np.zeros((k, 2), np.float32))
    _, shape, view, row, col = near
    pixel = np.stack([col * PIXELS_PER_CELL + size // 2, row * PIXELS_PER_CELL + size // 2],
                     axis=1).astype(np.float32)
    return FilterBank(words, view.copy(), shape.copy(), np.full(k, -1, np.int64), pixel)


def analyse(drawings: list[ShapeDrawings], params: AnalysisParams,
            labels: dict | None = None, triplets: list | None = None, fusion: str = "graph",
            progress=None, cancel=None, maps: np.ndarray | None = None,
            encoded: Encoding | None = None, cache_dir=None) -> AnalysisResult:
    """Cluster shapes by style and find their style words (unsupervised, labels or triplets).

    `maps`: the drawings' HOG maps (a sequence of (V, by, bx, C)) when the caller has them (the job
    reuses them to find style regions); computed here otherwise. `encoded`: the collection's
    `encode` with the same drawings and parameters, when the caller runs several analyses of
    one collection (the benchmark's modes). `fusion` replaces the style graph's fusion for
    comparisons (FUSIONS). `cache_dir`: where the default's vocabularies are kept (None: the
    user cache; False: nowhere)."""
    if params.method == "paper":
        from .paper_method import analyse_paper
        return analyse_paper(drawings, params, labels, triplets, progress, cancel, maps)
    if params.method != "default":
        raise InputError(f"unknown method '{params.method}', choose 'default' or 'paper'")
    prog = Progress.wrap(progress, cancel)
    names, y, classes, trip = _check_inputs(drawings, params, labels, triplets, fusion)
    n = len(drawings)
    n_clusters = params.n_clusters
    if n_clusters is not None and y is None and not 1 <= n_clusters <= n:
        raise InputError(f"asked for {n_clusters} clusters but there are only {n} shapes")
    if encoded is None:
        encoded = encode(drawings, params, maps, prog, cache_dir)
    timings = dict(encoded.timings)
    dicts, lines = encoded.dictionaries, encoded.lines
    # what the labels' classifier weighs (_label_metric_graph): every dictionary's words and
    # the line character
    features = None
    if y is not None:
        features = np.hstack([d.relative for d in dicts] + [lines])
        features = (features - features.mean(axis=0)) / (features.std(axis=0) + 1e-9)

    keeps = [np.ones(len(d.bank), bool) for d in dicts]
    prev, reading, k_gaps = None, None, None
    rounds, seen = [], set()
    for r in range(max(1, params.max_rounds)):
        t = time.perf_counter()
        prog.step("fuse", r, params.max_rounds)
        views, view_names, kinds = _views(dicts, keeps, lines, params.n_style_dims)
        pick_k = y is None and n_clusters is None               # chosen once, in round 0
        a, weights, a_choice = _style_graph(views, params, y, fusion, choice=pick_k)
        if r == 0:
            a_all = a
        else:                                 # the kept words refine the all-words graph
            a = graph.fuse([a_all, a])
        if weights is not None:               # one weight per kind of view, summed over dictionaries
            weights = np.bincount(kinds, weights, minlength=len(view_names))
        timings["fuse"] = timings.get("fuse", 0.0) + time.perf_counter() - t

        t = time.perf_counter()
        prog.step("cluster", r, params.max_rounds)
        if pick_k:
            k_gaps = _cluster_count_gaps(a_choice, n)
            n_clusters = graph.choose_n_clusters(k_gaps)
        clusters, conf, n_c, fused, reading = _cluster(a, features, params, y, trip, n_clusters,
                                                       reading, prog)   # chosen in round 0
        timings["cluster"] = timings.get("cluster", 0.0) + time.perf_counter() - t

        t = time.perf_counter()
        prog.step("reselect", r, params.max_rounds)
        sels = [reselect(d.relative, clusters, mu=params.mu, min_kept=params.min_filters)
                for d in dicts]
        timings["reselect"] = timings.get("reselect", 0.0) + time.perf_counter() - t
        changed = n_changed(prev, clusters)
        same_words = all(np.array_equal(s.keep, k) for s, k in zip(sels, keeps))
        # the word counts reported are the first dictionary's, whose words the result shows
        rounds.append({"round": r, "n_filters": int(keeps[0].sum()), "n_clusters": n_c,
                       "n_changed": changed, "n_selected": int(sels[0].keep.sum()),
                       "n_passed": sels[0].n_passed, "view_weights": [float(w) for w in weights]
                       if weights is not None else None,
                       "clusters": [int(c) for c in clusters]})
        state = (_partition_key(clusters), b"".join(s.keep.tobytes() for s in sels))
        if (prev is not None and changed == 0 and same_words) or state in seen:
            break
        seen.add(state)
        prev, keeps = clusters, [s.keep for s in sels]

    t = time.perf_counter()
    if fused is None:
        fused = _coordinates(a, params)
    if conf is None:
        conf = _soft_confidence(fused, clusters)
    timings["cluster"] += time.perf_counter() - t
    # the result's words: the first dictionary's (drawn with the analysis seed)
    bank, sel = dicts[0].bank, sels[0]
    final = np.flatnonzero(sel.keep)
    best = sel.scores.argmax(axis=0) if sel.scores.size else np.zeros(len(bank), np.int64)
    cluster_ids = np.unique(clusters)
    style_filters = [StyleFilter(cluster=int(cluster_ids[best[f]]), view=int(bank.view[f]),
                                 hog=bank.hog[f], source_shape=int(bank.shape[f]),
                                 source_seed=int(bank.seed[f]),
                                 source_pixel=(float(bank.pixel[f, 0]), float(bank.pixel[f, 1])),
                                 score=float(sel.score[f])) for f in final]
    word_cluster = np.full(len(bank), -1, np.int64)
    word_score = np.full(len(bank), -np.inf)
    for f, sf in zip(final, style_filters):
        word_cluster[f], word_score[f] = sf.cluster, sf.score
    predicted = [classes[c] for c in clusters] if classes is not None else None
    label_given = (y >= 0) if y is not None else np.zeros(n, bool)
    n_clusters = len(classes) if classes is not None else int(len(cluster_ids))
    agreement = None
    if y is None and trip is None and fusion == "graph":
        agreement = _dictionary_agreement(dicts, lines, params, clusters, n_clusters)
    prog.step("done", 1, 1)
    return AnalysisResult(names=names, clusters=np.asarray(clusters, np.int64),
                          n_clusters=n_clusters, fused=np.asarray(fused), confidence=conf,
                          classes=classes, predicted=predicted, label_given=label_given,
                          style_filters=style_filters,
                          view_weights=None if weights is None else np.asarray(weights),
                          view_names=view_names, rounds=rounds, timings=timings,
                          words=bank.hog, word_cluster=word_cluster, word_score=word_score,
                          k_gaps=k_gaps, dictionary_agreement=agreement)


def style_similarity(result: AnalysisResult) -> np.ndarray:
    """(N, N) style distance between shapes, from the fused features (clustering.style_distance)."""
    from .clustering import style_distance
    return np.asarray(style_distance(result.fused))
