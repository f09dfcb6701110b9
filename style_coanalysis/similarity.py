"""Style distance between analysed shapes, and the style space a result folder keeps for it.

Why a separate space: the later uses (find similar, suggest what to label, score triplets) run
after the analysis, from its result folder or the saved .blend, without re-drawing anything. They
need only the analysis' fused features (its spectral style coordinates), its clusters and
confidences, which shapes were labelled, and the metric learned from the constraints.

The distance is the squared Euclidean distance of the L2-normalised fused features (the same
ranking as `clustering.style_distance`, the cosine distance), plus one term for "the analysis put
the two shapes in different clusters". Without constraints every coordinate weighs 1 and the
cluster term 0. With triplets (or labels, turned into the triplets they imply) a non-negative
weight per term is learned by logistic loss on the triplets' margins, pulled toward the
unsupervised weights (Schultz & Joachims 2003, a diagonal metric from relative comparisons); the
pull's strength is chosen by cross-validation on the given triplets, so no constant fits one
collection.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.optimize import minimize
from scipy.special import expit, log1p
from sklearn.model_selection import KFold
from sklearn.preprocessing import normalize

from . import atomic
from .meshes import InputError

SPACE_FILE = "style_space.npz"
MAX_LABEL_TRIPLETS = 2000        # triplets drawn from given labels (enough to fit D + 1 weights)
REGULARISATION_GRID = (0.01, 0.1, 1.0, 10.0)
MIN_TRIPLETS_TO_LEARN = 10       # fewer: 3-fold cross-validation has nothing to choose with


def _pair_terms(x: np.ndarray, clusters: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """(P, D + 1) per-term distances of pairs (i, j): squared coordinate gaps, cluster differs."""
    gap = (x[i] - x[j]) ** 2
    return np.column_stack([gap, (clusters[i] != clusters[j]).astype(np.float64)])


class StyleMetric:
    """Non-negative weights of the style distance's terms, learned from triplets.

    fit(X, triplets, clusters): X (N, D) fused features, triplets (T, 3) indices (a closer to b
    than to c), clusters (N,). `weights_` (D + 1,), `alpha_` the chosen pull toward the
    unsupervised weights."""

    def __init__(self, alphas=REGULARISATION_GRID, n_splits: int = 3, random_state=0):
        self.alphas = alphas
        self.n_splits = n_splits
        self.random_state = random_state

    @staticmethod
    def prior(n_dims: int) -> np.ndarray:
        return np.r_[np.ones(n_dims), 0.0]

    def _solve(self, diff: np.ndarray, scale: np.ndarray, alpha: float, w0: np.ndarray):
        """argmin_w>=0 mean log(1 + exp(-diff @ w)) + alpha * |(w - w0) * scale|^2."""
        def f(w):
            m = diff @ w
            loss = np.mean(log1p(np.exp(-np.abs(m))) + np.maximum(-m, 0))
            g = -(diff * expit(-m)[:, None]).mean(axis=0)
            r = (w - w0) * scale
            return loss + alpha * r @ r, g + 2 * alpha * r * scale
        res = minimize(f, w0.copy(), jac=True, method="L-BFGS-B",
                       bounds=[(0, None)] * len(w0))
        return res.x

    def fit(self, X, triplets, clusters):
        x = normalize(np.asarray(X, np.float64))
        t = np.asarray(triplets, np.int64).reshape(-1, 3)
        clusters = np.asarray(clusters)
        w0 = self.prior(x.shape[1])
        # margin of each triplet per term: d(a, c) - d(a, b), positive when the term agrees
        diff = (_pair_terms(x, clusters, t[:, 0], t[:, 2])
                - _pair_terms(x, clusters, t[:, 0], t[:, 1]))
        # terms in comparable units: the pull acts on each weight times its typical size
        scale = np.abs(diff).mean(axis=0)
        scale[scale == 0] = 1.0
        if len(t) < MIN_TRIPLETS_TO_LEARN:
            self.alpha_, self.weights_ = None, w0
            return self
        folds = KFold(min(self.n_splits, len(t)), shuffle=True, random_state=self.random_state)
        scores = []
        for alpha in self.alphas:
            hits = 0.0
            for tr, te in folds.split(diff):
                w = self._solve(diff[tr], scale, alpha, w0)
                m = diff[te] @ w
                hits += (m > 0).sum() + 0.5 * (m == 0).sum()
            scores.append(hits)
        # ties go to the strongest pull (closest to the unsupervised metric)
        best = max(range(len(self.alphas)), key=lambda k: (scores[k], self.alphas[k]))
        self.alpha_ = float(self.alphas[best])
        self.weights_ = self._solve(diff, scale, self.alpha_, w0)
        return self


def label_triplets(label_given: np.ndarray, labels: list, rng: np.random.Generator,
                   limit: int = MAX_LABEL_TRIPLETS) -> np.ndarray:
    """(T, 3) triplets the given labels imply: a and b share a label, c has another."""
    idx = np.flatnonzero(label_given)
    lab = np.array([labels[i] for i in idx])
    out = set()
    same = [(a, b) for a in range(len(idx)) for b in range(len(idx)) if a != b and lab[a] == lab[b]]
    if not same:
        return np.zeros((0, 3), np.int64)
    for _ in range(limit * 20):
        if len(out) >= limit:
            break
        a, b = same[int(rng.integers(len(same)))]
        others = np.flatnonzero(lab != lab[a])
        if len(others) == 0:
            continue
        c = int(others[rng.integers(len(others))])
        out.add((int(idx[a]), int(idx[b]), int(idx[c])))
    return np.array(sorted(out), np.int64).reshape(-1, 3)


@dataclass
class StyleSpace:
    """What the later uses need from an analysis, keyed by shape name."""

    names: list
    features: np.ndarray               # (N, D) the analysis' fused features
    clusters: np.ndarray               # (N,) int
    confidence: np.ndarray             # (N,) in [0, 1]
    label_given: np.ndarray            # (N,) bool
    labels: list                       # (N,) str: given or predicted label, "" when none
    weights: np.ndarray = field(default=None)   # (D + 1,) the metric; None: unsupervised

    def __post_init__(self):
        self.features = np.asarray(self.features, np.float64)
        self.clusters = np.asarray(self.clusters, np.int64)
        self.confidence = np.asarray(self.confidence, np.float64)
        self.label_given = np.asarray(self.label_given, bool)
        self.labels = [str(s) for s in self.labels]
        self.names = [str(n) for n in self.names]
        if self.weights is None:
            self.weights = StyleMetric.prior(self.features.shape[1])
        self.weights = np.asarray(self.weights, np.float64)
        self._unit = normalize(self.features)

    # -- construction
    @classmethod
    def from_result(cls, result, triplets=None, random_state: int = 0) -> "StyleSpace":
        """From a `pipeline.AnalysisResult`; the metric is learned from `triplets` (names) if
        given, else from the triplets the result's given labels imply, else left unsupervised."""
        n = len(result.names)
        labels = list(result.predicted) if result.predicted is not None else [""] * n
        space = cls(list(result.names), result.fused, result.clusters, result.confidence,
                    result.label_given, labels)
        index = {name: i for i, name in enumerate(space.names)}
        if triplets:
            t = np.array([[index[x] for x in abc] for abc in triplets], np.int64)
        else:
            t = label_triplets(space.label_given, labels, np.random.default_rng(random_state))
        if len(t):
            metric = StyleMetric(random_state=random_state).fit(space.features, t, space.clusters)
            space.weights = metric.weights_
            space._unit = normalize(space.features)
        return space

    # -- distances
    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise InputError(f"'{name}' is not among the analysed shapes") from None

    def distances_from(self, i: int) -> np.ndarray:
        """(N,) style distance of every shape to shape i (0 for itself)."""
        others = np.arange(len(self.names))
        return _pair_terms(self._unit, self.clusters, np.full(len(others), i), others) @ self.weights

    def distance_matrix(self) -> np.ndarray:
        return np.stack([self.distances_from(i) for i in range(len(self.names))])

    def ranking(self, name: str, top: int | None = None) -> list[tuple[str, float]]:
        """[(name, distance)] of the other shapes, closest first (ties in name order)."""
        i = self.index(name)
        d = self.distances_from(i)
        order = [j for j in np.lexsort((self.names, d)) if j != i]
        return [(self.names[j], float(d[j])) for j in order[:top]]

    def triplet_accuracy(self, triplets) -> float:
        """Share of (a, b, c) (names or indices) where d(a, b) < d(a, c); a tie counts half."""
        t = np.array([[self.index(x) if isinstance(x, str) else int(x) for x in abc]
                      for abc in triplets], np.int64).reshape(-1, 3)
        if len(t) == 0:
            raise InputError("no triplets to score")
        dab = _pair_terms(self._unit, self.clusters, t[:, 0], t[:, 1]) @ self.weights
        dac = _pair_terms(self._unit, self.clusters, t[:, 0], t[:, 2]) @ self.weights
        return float(np.mean((dab < dac) + 0.5 * (dab == dac)))

    # -- storage
    def to_dict(self) -> dict:
        return {"names": np.array(self.names, dtype=str), "features": self.features,
                "clusters": self.clusters, "confidence": self.confidence,
                "label_given": self.label_given, "labels": np.array(self.labels, dtype=str),
                "weights": self.weights}

    def save(self, path) -> None:
        """Whole or not at all (`atomic`)."""
        atomic.write_bytes(path, atomic.npz_bytes(self.to_dict(), compress=False))

    @classmethod
    def from_dict(cls, d) -> "StyleSpace":
        return cls([str(n) for n in d["names"]], d["features"], d["clusters"], d["confidence"],
                   d["label_given"], [str(s) for s in d["labels"]], d["weights"])

    @classmethod
    def load(cls, result_dir) -> "StyleSpace":
        """The space an `analyze` run wrote into `result_dir`; InputError naming what is wrong."""
        folder = Path(result_dir)
        if not folder.is_dir():
            raise InputError(f"'{result_dir}' is not a folder (give the --out folder of analyze)")
        path = folder / SPACE_FILE
        if not path.is_file():
            raise InputError(f"'{folder}' holds no {SPACE_FILE}: not a result folder of "
                             "analyze, or one written before style similarity existed "
                             "(analyse again)")
        try:
            with np.load(path, allow_pickle=False) as d:
                space = cls.from_dict({k: d[k] for k in d.files})
        except (OSError, ValueError, KeyError) as exc:
            raise InputError(f"'{path}' is not a readable style space: {exc}") from None
        n = len(space.names)
        if space.features.shape[0] != n or len(space.clusters) != n or \
                len(space.weights) != space.features.shape[1] + 1:
            raise InputError(f"'{path}' is inconsistent (arrays of different lengths)")
        return space
