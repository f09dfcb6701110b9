"""Evaluation harness: how well does the analysis find style, against truth and baselines?

Renders a collection with ground truth once (through the drawing cache), then runs the analysis
in every mode and prints purity (paper eq. 5), NMI and ARI, mean and spread over seeds:
  unsupervised; 10/20/30 % labels; 100/200/300 triplets (drawn from the truth, seen by the
  analysis only as constraints); PSLF replaced by concatenation, PCA, CCA and max-pooling on the
  same per-view features; trivial baselines (ink density + orientation histogram of the drawings,
  raw size, global shape); a view-count sweep and an eta sweep; purity against *category* too.
Writes bench/results/eval_<collection>.json and PNG plots beside it.

    python bench/evaluate.py --collection sample [--size 120] [--seeds 3] [--renderer freestyle]
    python bench/evaluate.py --collection voxel --per-class 10
    python bench/evaluate.py --quick         # a few configurations only
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from style_coanalysis import metrics, pipeline  # noqa: E402
from style_coanalysis.evaluation import baselines  # noqa: E402
from style_coanalysis.blender.batch import draw_collection  # noqa: E402
from style_coanalysis.blender.job import seed_subset  # noqa: E402
from style_coanalysis.meshes import normalise  # noqa: E402
from style_coanalysis.params import AnalysisParams, DrawingSettings  # noqa: E402

RESULTS = ROOT / "bench" / "results"


def load(collection: str, size: int, per_class: int | None, seed: int):
    if collection == "sample":
        from style_coanalysis.sample import generate
        return generate(size=size, seed=seed)
    from style_coanalysis.evaluation.voxels import load_hu2017
    return load_hu2017(per_class=per_class, seed=seed)


def pick_labels(styles, fraction, rng):
    """A random labelled subset with every style present (as a user would label a few of each)."""
    n = len(styles)
    idx = [int(rng.choice(np.flatnonzero(styles == s))) for s in np.unique(styles)]
    rest = rng.permutation([i for i in range(n) if i not in idx])
    idx += list(rest[: max(0, int(round(fraction * n)) - len(idx))])
    return idx


def pick_triplets(styles, count, rng):
    out = []
    while len(out) < count:
        a, b, c = rng.choice(len(styles), 3, replace=False)
        if styles[a] == styles[b] != styles[c]:
            out.append((int(a), int(b), int(c)))
    return out


def view_subset(d, views):
    return replace(d, images=d.images[views], cameras=d.cameras[views],
                   seed_visible=d.seed_visible[views], seed_pixels=d.seed_pixels[views],
                   vertex_visible=d.vertex_visible[views])


def summarise(runs):
    out = {}
    for key in runs[0]:
        vals = np.array([r[key] for r in runs], float)
        out[key] = {"mean": float(vals.mean()), "std": float(vals.std()), "min": float(vals.min()),
                    "max": float(vals.max())}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--collection", choices=("sample", "voxel"), default="sample")
    ap.add_argument("--size", type=int, default=120)
    ap.add_argument("--per-class", type=int, default=None, help="voxel set: shapes per style x category")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--renderer", default="freestyle")
    ap.add_argument("--jobs", type=int, default=0)
    ap.add_argument("--cache", default=None)
    ap.add_argument("--quick", action="store_true", help="unsupervised, 20%% labels, 300 triplets, baselines")
    ap.add_argument("--rounds", type=int, default=AnalysisParams().max_rounds)
    ap.add_argument("--suggestive-contours", action="store_true", help="Freestyle with suggestive contours")
    ap.add_argument("--only", nargs="+", default=None, help="run only rows whose name contains one of these")
    args = ap.parse_args()

    t0 = time.perf_counter()
    meshes = load(args.collection, args.size, args.per_class, 0)
    styles = np.array([m.truth["style"] for m in meshes])
    cats = np.array([m.truth["category"] for m in meshes])
    n_styles = len(np.unique(styles))
    settings = DrawingSettings(renderer=args.renderer, n_seeds=90,
                               suggestive_contours=args.suggestive_contours)
    drawings, skipped = draw_collection(meshes, settings, args.cache, jobs=args.jobs,
                                        progress=lambda s, d, t: print(f"\r{s} {d}/{t}", end="",
                                                                       file=sys.stderr))
    print(file=sys.stderr)
    keep = {d.name for d in drawings}
    sel = np.array([m.name in keep for m in meshes])
    meshes = [m for m in meshes if m.name in keep]
    styles, cats = styles[sel], cats[sel]
    drawings = [seed_subset(d, 30) for d in drawings]
    render_s = time.perf_counter() - t0
    names = [m.name for m in meshes]
    print(f"{args.collection}: {len(meshes)} shapes, {n_styles} styles, {len(np.unique(cats))} "
          f"categories; drawings in {render_s:.1f} s ({args.renderer}); skipped {len(skipped)}")

    rows = {}

    def record(key, fn):
        if args.only and not any(o in key for o in args.only):
            return
        runs, cat_runs, secs = [], [], []
        for seed in range(args.seeds):
            rng = np.random.default_rng(1000 + seed)
            t = time.perf_counter()
            try:
                pred = fn(seed, rng)
            except ValueError as exc:   # a configuration that cannot apply here (e.g. max-pooling
                print(f"{key:32s} n/a: {exc}")  # over views of different sizes)
                rows[key] = {"n/a": str(exc)}
                return
            secs.append(time.perf_counter() - t)
            runs.append(metrics.score(pred, styles))
            cat_runs.append({"purity": metrics.score(pred, cats)["purity"]})
        rows[key] = {"style": summarise(runs), "category": summarise(cat_runs),
                     "seconds": float(np.mean(secs)), "n_clusters": int(len(np.unique(pred)))}
        s = rows[key]["style"]
        print(f"{key:32s} purity {s['purity']['mean']:.3f} ± {s['purity']['std']:.3f}  "
              f"NMI {s['nmi']['mean']:.3f}  ARI {s['ari']['mean']:.3f}  "
              f"category purity {rows[key]['category']['purity']['mean']:.3f}  "
              f"k={rows[key]['n_clusters']}  {rows[key]['seconds']:.1f} s", flush=True)

    def analysis(seed, labels=None, triplets=None, fusion="pslf", k=None, ds=None, **kw):
        params = replace(AnalysisParams(), random_state=seed, n_clusters=k, max_rounds=args.rounds, **kw)
        res = pipeline.analyse(ds or drawings, params, labels=labels, triplets=triplets, fusion=fusion)
        return res.clusters

    # trivial baselines first: a gain counts only where it beats them
    line_feats = baselines.line_statistics([d.images for d in drawings])
    record("baseline: line statistics", lambda s, r: baselines.cluster_baseline(line_feats, n_styles, s))
    record("baseline: raw size", lambda s, r: baselines.cluster_baseline(
        baselines.raw_size(meshes), n_styles, s))
    record("baseline: global shape", lambda s, r: baselines.cluster_baseline(
        baselines.global_shape_features([normalise(m) for m in meshes]), n_styles, s))

    record("unsupervised (auto k)", lambda s, r: analysis(s))
    record("unsupervised (k = true)", lambda s, r: analysis(s, k=n_styles))
    for fusion in ("concat", "pca", "cca", "maxpool"):
        record(f"unsupervised {fusion} (k = true)", lambda s, r, f=fusion: analysis(s, fusion=f, k=n_styles))
    fractions = (0.2,) if args.quick else (0.1, 0.2, 0.3)
    for frac in fractions:
        def lab(s, r, frac=frac, fusion="pslf"):
            idx = pick_labels(styles, frac, r)
            return analysis(s, labels={names[i]: str(styles[i]) for i in idx}, fusion=fusion)
        record(f"labels {int(frac * 100)}%", lab)
    counts = (300,) if args.quick else (100, 200, 300)
    for count in counts:
        def tri(s, r, count=count):
            t = pick_triplets(styles, count, r)
            return analysis(s, triplets=[(names[a], names[b], names[c]) for a, b, c in t], k=n_styles)
        record(f"triplets {count}", tri)
    if not args.quick:
        for fusion in ("concat", "pca", "cca", "maxpool"):
            record(f"labels 20% {fusion}", lambda s, r, f=fusion: analysis(
                s, labels={names[i]: str(styles[i]) for i in pick_labels(styles, 0.2, r)}, fusion=f))
            record(f"triplets 100 {fusion}", lambda s, r, f=fusion: analysis(
                s, triplets=[(names[a], names[b], names[c]) for a, b, c in pick_triplets(styles, 100, r)],
                k=n_styles, fusion=f))
        for nv in (1, 2, 3, 4, 6, 8, 12):
            views = np.linspace(0, 12, nv, endpoint=False).astype(int)
            ds = [view_subset(d, views) for d in drawings]
            record(f"views {nv:2d} (k = true)", lambda s, r, ds=ds: analysis(s, k=n_styles, ds=ds))
        for eta in (0.1, 0.2, 0.3, 0.5, 0.7, 0.9):
            record(f"eta {eta:.1f} (k = true)", lambda s, r, eta=eta: analysis(s, k=n_styles, eta=eta))

    RESULTS.mkdir(parents=True, exist_ok=True)
    stem = (f"eval_{args.collection}{'_sc' if args.suggestive_contours else ''}"
            f"{'_quick' if args.quick else ''}{'_only' if args.only else ''}")
    out = {"collection": args.collection, "n_shapes": len(meshes), "renderer": args.renderer,
           "suggestive_contours": args.suggestive_contours,
           "seeds": args.seeds, "render_seconds": render_s, "chance": float(
               max(np.mean(styles == s) for s in np.unique(styles))), "rows": rows}
    (RESULTS / f"{stem}.json").write_text(json.dumps(out, indent=2))
    plot(rows, RESULTS / f"{stem}.png")
    print(f"wrote {RESULTS / (stem + '.json')} and .png")


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    keys = [k for k in rows if "n/a" not in rows[k]]
    means = [rows[k]["style"]["purity"]["mean"] for k in keys]
    stds = [rows[k]["style"]["purity"]["std"] for k in keys]
    cat = [rows[k]["category"]["purity"]["mean"] for k in keys]
    fig, ax = plt.subplots(figsize=(8, 0.3 * len(keys) + 1.5))
    y = np.arange(len(keys))
    ax.barh(y, means, xerr=stds, color="tab:orange", label="style purity")
    ax.plot(cat, y, "k|", markersize=12, label="category purity")
    ax.set_yticks(y, keys)
    ax.invert_yaxis()
    ax.set_xlim(0, 1)
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


if __name__ == "__main__":
    main()
