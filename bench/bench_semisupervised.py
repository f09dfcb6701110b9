"""Semi-supervised style clustering on the sample collection's per-view encoded features.

Prints purity (paper eq. 5) against the true STYLE, mean over 3 seeds, for
  * 0/10/20/30 % style labels (stratified), PSLF eq. 2 vs concat/PCA/CCA/max-pool fusion
    (baselines spread the labels with LabelSpreading, as pipeline.py does); purity over all
    shapes (labelled ones keep their label) and accuracy on the unlabelled ones;
  * 0/100/200/300 triplets (a, b, c) DERIVED FROM THE TRUE LABELS (style a == style b != style c,
    drawn at random), TripletClustering with C = number of styles on every fusion;
  * triplet prediction accuracy on 2,000 HELD-OUT label-derived triplets (disjoint from the
    training ones), from style_distance of the unsupervised fused features and in the metric
    learned from 300 training triplets.
0 % labels / 0 triplets is the unsupervised run (C fixed to the number of styles).

Features are cached in /tmp/semi/sample_views.npz (about 40 s to build from the drawing cache).

    nice .venv/bin/python bench/bench_semisupervised.py [--seeds 3] [--fusions pslf,concat,...]
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from sklearn.metrics.cluster import contingency_matrix  # noqa: E402
from sklearn.semi_supervised import LabelSpreading  # noqa: E402

from style_coanalysis import fusion as fusion_mod  # noqa: E402
from style_coanalysis.clustering import (SelfTuningSpectralClustering, TripletClustering,  # noqa: E402
                                         predict_triplets, style_distance)
from style_coanalysis.pslf import PSLF  # noqa: E402

CACHE = Path(os.environ.get("SEMI_CACHE", "/tmp/semi/sample_views.npz"))


def build_cache(path):
    from style_coanalysis.blender.batch import draw_collection
    from style_coanalysis.blender.job import seed_subset
    from style_coanalysis.encoding import build_filter_bank, correlate_pooled, view_features
    from style_coanalysis.features import hog_images
    from style_coanalysis.params import AnalysisParams, DrawingSettings
    from style_coanalysis.patches import extract_patches
    from style_coanalysis.sample import generate
    ms = generate(120, 0)
    d, _ = draw_collection(ms, DrawingSettings(renderer="freestyle", n_seeds=90), None, jobs=1)
    d = [seed_subset(x, 30) for x in d]
    p = AnalysisParams()
    patches = extract_patches(d, size=p.patch_size)
    maps = np.stack([hog_images(x.images) for x in d])
    bank = build_filter_bank(maps, patches.shape, patches.view, patches.seed, patches.centre,
                             p.patch_size, p.n_representatives, p.random_state)
    n, nv, size = len(d), d[0].n_views, tuple(d[0].images.shape[1:3])
    pooled = np.zeros((n, len(bank), 5), np.float32)
    for v in range(nv):
        idx = np.flatnonzero(bank.view == v)
        if len(idx):
            pooled[:, idx] = correlate_pooled(maps[:, v], bank.hog[idx], size)
    views = view_features(pooled, bank.view, None, nv)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez(path, *views, style=np.array([m.truth["style"] for m in ms]),
             category=np.array([m.truth["category"] for m in ms]))


def load(path):
    z = np.load(path)
    k = sorted((f for f in z.files if f.startswith("arr_")), key=lambda s: int(s[4:]))
    views = [z[f] for f in k]
    return (views, np.unique(z["style"], return_inverse=True)[1],
            np.unique(z["category"], return_inverse=True)[1])


def purity(y, lab):
    c = contingency_matrix(y, lab)
    return c.max(axis=0).sum() / c.sum()


def label_subset(y, frac, seed):
    rng = np.random.RandomState(seed)
    out = np.full(len(y), -1)
    for c in np.unique(y):
        idx = np.flatnonzero(y == c)
        out[rng.choice(idx, max(1, int(round(frac * len(idx)))), replace=False)] = c
    return out


def label_triplets(y, t, rng, exclude=frozenset()):
    out, seen = [], set(exclude)
    while len(out) < t:
        a, b, c = rng.randint(len(y), size=3)
        if a != b and y[a] == y[b] != y[c] and (a, b, c) not in seen:
            seen.add((a, b, c))
            out.append((a, b, c))
    return np.array(out, dtype=np.int64).reshape(-1, 3)


def fuse(name, views, y=None, seed=0):
    if name == "pslf":
        m = PSLF(random_state=seed)
        return m.fit_transform(views, y=y), m
    cls = {"concat": "ConcatFusion", "pca": "PCAFusion", "cca": "CCAFusion",
           "maxpool": "MaxPoolFusion"}[name]
    return np.asarray(getattr(fusion_mod, cls)().fit_transform(views)), None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--fusions", default="pslf,concat,pca,cca,maxpool")
    args = ap.parse_args()
    if not CACHE.exists():
        build_cache(CACHE)
    views, ys, yc = load(CACHE)
    C = len(np.unique(ys))
    fusions = args.fusions.split(",")
    seeds = range(args.seeds)
    print(f"sample collection: {len(ys)} shapes, {len(views)} views, {C} styles; "
          f"mean over {args.seeds} seeds; purity against STYLE")
    unsup = {f: fuse(f, views, seed=0)[0] for f in fusions}

    print("\n== labels: purity all shapes (accuracy on unlabelled) ==")
    print("fusion    " + "".join(f"{p:>16}" for p in ("0%", "10%", "20%", "30%")))
    for f in fusions:
        row = []
        for frac in (0.0, 0.1, 0.2, 0.3):
            pu, ac = [], []
            for s in seeds:
                if frac == 0:
                    lab = SelfTuningSpectralClustering(C, random_state=s).fit_predict(unsup[f])
                    pu.append(purity(ys, lab)); ac.append(np.nan)
                    continue
                yl = label_subset(ys, frac, s)
                u = yl < 0
                if f == "pslf":
                    V, m = fuse(f, views, yl, seed=s)
                    pred = np.asarray(m.transduction_)
                else:
                    V = unsup[f]
                    pred = LabelSpreading(kernel="knn", n_neighbors=7, max_iter=200) \
                        .fit(V, yl).transduction_
                pred = pred.copy(); pred[~u] = yl[~u]
                pu.append(purity(ys, pred)); ac.append(np.mean(pred[u] == ys[u]))
            acs = "" if frac == 0 else f" ({np.nanmean(ac):.3f})"
            row.append(f"{np.mean(pu):.3f}{acs}")
        print(f"{f:10s}" + "".join(f"{r:>16}" for r in row), flush=True)

    print("\n== triplets (label-derived): purity, TripletClustering C=%d ==" % C)
    print("fusion    " + "".join(f"{t:>10}" for t in (0, 100, 200, 300)))
    for f in fusions:
        row = []
        for t in (0, 100, 200, 300):
            pu = []
            for s in seeds:
                T = label_triplets(ys, t, np.random.RandomState(s))
                lab = TripletClustering(C, random_state=s).fit_predict(unsup[f], T)
                assert len(np.unique(lab)) == C
                pu.append(purity(ys, lab))
            row.append(np.mean(pu))
        print(f"{f:10s}" + "".join(f"{r:10.3f}" for r in row), flush=True)

    print("\n== triplet prediction on 2000 held-out label-derived triplets ==")
    print("fusion      unsupervised   metric from 300 triplets")
    for f in fusions:
        a0, a1 = [], []
        for s in seeds:
            rng = np.random.RandomState(s)
            T = label_triplets(ys, 300, rng)
            H = label_triplets(ys, 2000, np.random.RandomState(1000 + s),
                               exclude={tuple(x) for x in T})
            a0.append(predict_triplets(style_distance(unsup[f]), H).mean())
            m = TripletClustering(C, random_state=s).fit(unsup[f], T)
            a1.append(predict_triplets(style_distance(unsup[f], m.metric_weights_), H).mean())
        print(f"{f:10s}{np.mean(a0):14.3f}{np.mean(a1):14.3f}", flush=True)


if __name__ == "__main__":
    t0 = time.time()
    main()
    print(f"\n({time.time() - t0:.0f} s)")
