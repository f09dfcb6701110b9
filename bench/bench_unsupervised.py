"""Unsupervised style clustering (issue 5): style vs category purity/NMI beside trivial baselines.

    nice .venv/bin/python bench/bench_unsupervised.py [--voxels PER_CLASS] [--seeds 3]

Sample collection: `sample.generate(120, 0)`, Freestyle drawings from the cache (90 seeds rendered,
the first 30 used). Voxels: `voxels.load_hu2017(per_class=...)` (skipped when its drawings are
not all cached). Prints, per seed and as the mean over seeds, the analysis' style and category
purity/NMI, the number of clusters it chose, filters and purity per reselection round, and the
line-statistics and global-shape baselines (k-means with the same number of clusters). Ground
truth is used only here, to score.
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from style_coanalysis.evaluation.baselines import cluster_baseline, global_shape_features, line_statistics  # noqa: E402
from style_coanalysis.metrics import nmi, purity  # noqa: E402
from style_coanalysis.params import AnalysisParams, DrawingSettings  # noqa: E402
from style_coanalysis.pipeline import analyse  # noqa: E402


def drawings_for(meshes):
    from style_coanalysis.blender.batch import draw_collection
    from style_coanalysis.blender.job import seed_subset
    d, _ = draw_collection(meshes, DrawingSettings(renderer="freestyle", n_seeds=90), None, jobs=1)
    return [seed_subset(x, 30) for x in d]


def cached_only(meshes):
    """The meshes whose drawings are already in the default cache (never render here)."""
    from style_coanalysis.blender.batch import CODE_VERSION, DrawingCache, cache_key, normalise
    settings = DrawingSettings(renderer="freestyle", n_seeds=90)
    cache = DrawingCache(None)
    return [m for m in meshes if cache.load(cache_key(normalise(m, settings.up), settings,
                                                      CODE_VERSION)) is not None]


def run(name, meshes, seeds):
    t = time.perf_counter()
    drawings = drawings_for(meshes)
    print(f"\n== {name}: {len(drawings)} shapes (drawings loaded in {time.perf_counter() - t:.1f} s)")
    st = np.array([m.truth["style"] for m in meshes])
    ca = np.array([m.truth["category"] for m in meshes])
    rows = {"analysis": [], "line statistics": [], "global shape": []}
    lines = line_statistics([d.images for d in drawings])
    glob = global_shape_features(meshes)
    for seed in seeds:
        t = time.perf_counter()
        res = analyse(drawings, replace(AnalysisParams(), random_state=seed))
        sec = time.perf_counter() - t
        c = res.clusters
        rows["analysis"].append((purity(c, st), purity(c, ca), nmi(c, st), nmi(c, ca), res.n_clusters))
        per_round = ", ".join(f"r{r['round']}: {r['n_filters']} filters -> style "
                              f"{purity(r['clusters'], st):.2f}" for r in res.rounds)
        print(f"seed {seed}: {sec:5.1f} s, {res.n_clusters} clusters, style {rows['analysis'][-1][0]:.3f} "
              f"cat {rows['analysis'][-1][1]:.3f} | {per_round}", flush=True)
        for bname, feats in (("line statistics", lines), ("global shape", glob)):
            b = cluster_baseline(feats, res.n_clusters, seed)
            rows[bname].append((purity(b, st), purity(b, ca), nmi(b, st), nmi(b, ca), res.n_clusters))
    print(f"{'mean over ' + str(len(seeds)) + ' seeds':18s} {'style pur':>9s} {'cat pur':>8s} "
          f"{'style NMI':>9s} {'cat NMI':>8s} {'C':>4s}")
    for k, v in rows.items():
        m = np.mean(v, axis=0)
        print(f"{k:18s} {m[0]:9.3f} {m[1]:8.3f} {m[2]:9.3f} {m[3]:8.3f} {m[4]:4.1f}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--voxels", type=int, default=0, help="models per style x category (0: skip)")
    ap.add_argument("--no-sample", action="store_true")
    a = ap.parse_args()
    seeds = list(range(a.seeds))
    if not a.no_sample:
        from style_coanalysis.sample import generate
        run("sample collection", generate(120, 0), seeds)
    if a.voxels:
        from style_coanalysis.evaluation.voxels import load_hu2017
        meshes = cached_only(load_hu2017(per_class=a.voxels))
        run(f"hu2017 voxels, per_class={a.voxels}, cached {len(meshes)}", meshes, seeds)


if __name__ == "__main__":
    main()
