"""What to label next: style purity against the number of labels, suggested vs random picks.

Per collection and seed, starting from the unsupervised analysis (k chosen automatically):
  * suggested: `suggest.suggest` picks the next shapes from the latest analysis' style space, an
    oracle labels them with their true style, the analysis runs again with all labels so far, and
    so on up to each budget (5%, 10%, 20% of the collection by default);
  * random: the same budgets of shapes drawn uniformly at random (nested, no look at the truth;
    a draw naming one style only is analysed unsupervised, as the command would refuse it).
Ground truth is read only to answer the oracle and to score. Goal (issue 14): suggested picks
reach the random picks' 20%-label purity with half as many labels.

    python bench/bench_suggest.py --collections sample-120 hu2017-60-0 --seeds 3
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

from style_coanalysis import metrics, pipeline  # noqa: E402
from style_coanalysis.evaluation import benchmark as B  # noqa: E402
from style_coanalysis.params import AnalysisParams  # noqa: E402
from style_coanalysis.similarity import StyleSpace  # noqa: E402
from style_coanalysis.suggest import suggest  # noqa: E402

FRACTIONS = (0.05, 0.1, 0.2)


def analyse(coll, labelled: list[int], seed: int):
    styles = coll.truth["style"]
    labels = {coll.names[i]: str(styles[i]) for i in labelled}
    if len(set(labels.values())) < 2:
        labels = None
    res = pipeline.analyse(coll.drawings, AnalysisParams(random_state=seed), labels=labels,
                           maps=coll.maps)
    return res, metrics.purity(np.asarray(res.clusters), styles)


def run(coll, seeds, budgets, log) -> dict:
    out = {"suggested": [], "random": [], "unsupervised": []}
    for seed in seeds:
        t0 = time.perf_counter()
        res0, p0 = analyse(coll, [], seed)
        out["unsupervised"].append(p0)
        # suggested, iteratively
        res, labelled, row = res0, [], []
        for b in budgets:
            space = StyleSpace.from_result(res, random_state=seed)
            mask = np.zeros(len(coll.names), bool)
            mask[labelled] = True
            picks = suggest(space, b - len(labelled), labelled=mask)
            labelled += [space.index(p.name) for p in picks]
            res, p = analyse(coll, labelled, seed)
            row.append(p)
        out["suggested"].append(row)
        # random, nested
        order = np.random.default_rng([9000 + seed]).permutation(len(coll.names))
        row_r = [analyse(coll, list(order[:b]), seed)[1] for b in budgets]
        out["random"].append(row_r)
        log(f"  {coll.name} seed {seed}: unsupervised {p0:.3f}; labels {budgets}: suggested "
            + " ".join(f"{p:.3f}" for p in row) + ", random " + " ".join(f"{p:.3f}" for p in row_r)
            + f" [{time.perf_counter() - t0:.0f} s]")
    return out


def table(results: dict) -> str:
    lines = ["| collection | N | labels | suggested | random | unsupervised (0 labels) |",
             "|---|---:|---:|---|---|---|"]
    for name, r in results.items():
        s, rnd, u = np.array(r["suggested"]), np.array(r["random"]), np.array(r["unsupervised"])
        for k, b in enumerate(r["budgets"]):
            lines.append(f"| {name} | {r['n']} | {b} | {s[:, k].mean():.3f} ± {s[:, k].std():.3f}"
                         f" | {rnd[:, k].mean():.3f} ± {rnd[:, k].std():.3f}"
                         f" | {u.mean():.3f} ± {u.std():.3f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--collections", nargs="+", default=["sample-120", "hu2017-60-0"])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--fractions", type=float, nargs="+", default=list(FRACTIONS))
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--json", default=str(ROOT / "bench" / "results" / "suggest.json"))
    args = ap.parse_args(argv)

    def log(msg):
        print(msg, file=sys.stderr, flush=True)
    results = {}
    for name in args.collections:
        coll = B.load_collection(name, jobs=args.jobs, log=log)
        n = len(coll.names)
        budgets = sorted({max(2, int(round(f * n))) for f in args.fractions})
        results[name] = {"n": n, "budgets": budgets} | run(coll, range(args.seeds), budgets, log)
        print(table({name: results[name]}), flush=True)
    print(f"\nstyle purity, mean ± std over seeds {', '.join(map(str, range(args.seeds)))}")
    print(table(results))
    Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
