"""Style similarity: accuracy on held-out triplets ("a is closer in style to b than to c").

The triplets are label-derived, not human judgements: a and b share the style label, c has
another. Held-out test triplets never equal a training triplet. Per collection and seed:
  * unsupervised: the analysis with k chosen automatically (what a user gets with no input);
  * triplets-50 / triplets-300: the analysis given that many training triplets (k given, as in
    the generalisation benchmark) and the metric `similarity.StyleSpace` learns from them;
baselines on the same test triplets: Euclidean distance of the standardised global-shape features
(`evaluation.baselines.global_shape_features`), of the whole-image line statistics, and chance 0.5.

Collections: `sample-120` (test: 2000 label-derived triplets drawn apart from the training
ones); `hu2017-train-160` (160 voxel shapes of the set's training split, stratified by style and
category, and the set's own `train_triplets.txt` rows among them, which are label-derived too
(all 30000 rows agree with the style labels): training triplets drawn from those rows, the others
held out for the test); any benchmark collection (`hu2017-all` is the same with every shape,
too slow to analyse 9 times on this shared machine; `hu2017-60-0`, ...: label-derived triplets
as for the sample).

    python bench/bench_similarity.py --collections sample-120 hu2017-train-160 --seeds 3
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sklearn.preprocessing import StandardScaler  # noqa: E402

from style_coanalysis import pipeline  # noqa: E402
from style_coanalysis.evaluation import baselines  # noqa: E402
from style_coanalysis.evaluation import benchmark as B  # noqa: E402
from style_coanalysis.evaluation.voxels import resolve_root  # noqa: E402
from style_coanalysis.params import AnalysisParams  # noqa: E402
from style_coanalysis.similarity import StyleSpace  # noqa: E402

N_TEST = 2000
MODES = ("unsupervised", "triplets-50", "triplets-300")


def file_triplets(names) -> np.ndarray | None:
    """The voxel set's train_triplets.txt rows among `names`, as indices (None if absent)."""
    path = Path(resolve_root()) / "train_triplets.txt"
    if not path.is_file():
        return None
    index = {n: i for i, n in enumerate(names)}
    rows = [[index.get(x.removesuffix(".obj")) for x in line.split()]
            for line in path.read_text().splitlines() if len(line.split()) == 3]
    return np.array([r for r in rows if None not in r], np.int64).reshape(-1, 3)


def hu2017_train(size: int, log):
    """`size` shapes of the voxel set's training split (stratified), drawn as the benchmark."""
    train = {line.strip().removesuffix(".obj")
             for line in (Path(resolve_root()) / "train.txt").read_text().split()}
    pool = [m for m in B._voxel_pool() if m.name in train]
    idx = B.stratified_subset([m.truth["style"] for m in pool],
                              [m.truth["category"] for m in pool], size, 0)
    meshes = [pool[i] for i in idx]
    kept, drawings, maps, skipped = B.draw(meshes, 1, log, f"hu2017-train-{size}")
    truth = {k: np.array([str(m.truth[k]) for m in kept]) for k in ("style", "category")}
    return B.Collection(f"hu2017-train-{size}", "voxel training split subset", kept, drawings,
                        maps, truth, list(skipped))


def split_triplets(coll, seed: int, n_train: int):
    """(train, test) triplet index arrays for one seed; disjoint."""
    rng = np.random.default_rng([7000 + seed, n_train])
    pool = file_triplets(coll.names) if coll.name.startswith("hu2017") else None
    if pool is not None and len(pool) >= n_train + 100:
        perm = rng.permutation(len(pool))
        return pool[perm[:n_train]], pool[perm[n_train:n_train + N_TEST]]
    both = np.array(B.pick_triplets(coll.truth["style"], n_train + N_TEST, rng), np.int64)
    return both[:n_train], both[n_train:]


def accuracy(D: np.ndarray, t: np.ndarray) -> float:
    dab, dac = D[t[:, 0], t[:, 1]], D[t[:, 0], t[:, 2]]
    return float(np.mean((dab < dac) + 0.5 * (dab == dac)))


def euclidean(X) -> np.ndarray:
    X = StandardScaler().fit_transform(np.asarray(X, np.float64))
    return ((X[:, None] - X[None]) ** 2).sum(-1)


def run(coll, seeds, log) -> dict:
    k = coll.n_styles
    base_feats = {"global shape": baselines.global_shape_features(coll.meshes),
                  "line statistics": baselines.line_statistics([d.images for d in coll.drawings])}
    base_d = {b: euclidean(X) for b, X in base_feats.items()}
    out = {m: [] for m in MODES}
    for seed in seeds:
        for mode in MODES:
            n_train = 0 if mode == "unsupervised" else int(mode.split("-")[1])
            train, test = split_triplets(coll, seed, max(n_train, 1))
            train = train[:n_train]
            trip = [tuple(coll.names[i] for i in abc) for abc in train] or None
            params = AnalysisParams(n_clusters=None if trip is None else k, random_state=seed)
            t0 = time.perf_counter()
            res = pipeline.analyse(coll.drawings, params, triplets=trip, maps=coll.maps)
            space = StyleSpace.from_result(res, triplets=trip, random_state=seed)
            unweighted = StyleSpace.from_result(res)
            row = {"seed": seed, "n_train": n_train, "n_test": len(test),
                   "style distance": space.triplet_accuracy(test),
                   "fused features, no metric": unweighted.triplet_accuracy(test),
                   "cluster weight": float(space.weights[-1]),
                   "seconds": time.perf_counter() - t0}
            row.update({b: accuracy(D, test) for b, D in base_d.items()})
            out[mode].append(row)
            log(f"  {coll.name} seed {seed} {mode}: style distance {row['style distance']:.3f}"
                f" (no metric {row['fused features, no metric']:.3f}), global shape "
                f"{row['global shape']:.3f}, line statistics {row['line statistics']:.3f}"
                f" [{row['seconds']:.0f} s]")
    return out


COLUMNS = ("style distance", "fused features, no metric", "global shape", "line statistics")


def table(results: dict) -> str:
    lines = ["| collection | N | mode | test triplets | " + " | ".join(COLUMNS) + " | chance |",
             "|---|---:|---|---:|" + "---|" * len(COLUMNS) + "---:|"]
    for name, r in results.items():
        for mode, rows in r["modes"].items():
            cells = []
            for c in COLUMNS:
                v = np.array([row[c] for row in rows])
                cells.append(f"{v.mean():.3f} ± {v.std():.3f}")
            lines.append(f"| {name} | {r['n']} | {mode} | {rows[0]['n_test']} | "
                         + " | ".join(cells) + " | 0.5 |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--collections", nargs="+", default=["sample-120", "hu2017-all"])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--json", default=str(ROOT / "bench" / "results" / "similarity.json"))
    args = ap.parse_args(argv)

    def log(msg):
        print(msg, file=sys.stderr, flush=True)
    results = {}
    for name in args.collections:
        coll = (hu2017_train(int(name.rsplit("-", 1)[1]), log)
                if name.startswith("hu2017-train-") else
                B.load_collection(name, jobs=args.jobs, log=log))
        results[name] = {"n": len(coll.names), "modes": run(coll, range(args.seeds), log)}
        print(table({name: results[name]}), flush=True)
    print("\nmean ± std over seeds " + ", ".join(map(str, range(args.seeds))))
    print(table(results))
    Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
