"""Which fusion of the default method's views holds across collections? (issue 11, item 3)

The default fuses its views (structure-relative words at every rung of the neighbour ladder, and
the line character) as graphs. This prints, for the same views, style purity (mean +- std over
seeds) with the fusion replaced by PSLF (paper eq. 1/2, its learned view weights), by
concatenation and by PCA of the concatenation, beside line statistics, on collections of
different sources and make-ups. Modes: k given, and 20% labels.

    python bench/bench_fusion.py [--collections sample-120 collection2 ...] [--seeds 3]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from style_coanalysis import pipeline  # noqa: E402
from style_coanalysis.evaluation import benchmark as B  # noqa: E402

FUSIONS = ("graph", "pslf", "concat", "pca")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--collections", nargs="+",
                    default=["sample-120", "sample-cats-1", "collection2", "hu2017-60-0", "hu2017-60-1"])
    ap.add_argument("--modes", nargs="+", default=["k", "labels-20%"])
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    rows = []
    for name in args.collections:
        coll = B.load_collection(name)
        for fusion in FUSIONS:
            def run(d, p, lab, tri, maps, fusion=fusion):
                return pipeline.analyse(d, p, labels=lab, triplets=tri, maps=maps, fusion=fusion)
            res = B.evaluate([coll], modes=args.modes, methods=["default"], seeds=args.seeds,
                             analyse_fn=run, stability=False)
            for mode in args.modes:
                s = res["collections"][coll.name]["modes"][mode]["default"]["summary"]["purity"]
                rows.append((name, mode, fusion, s["mean"], s["std"]))
                print(f"{name:14s} {mode:11s} {fusion:7s} purity {s['mean']:.3f} +- {s['std']:.3f}",
                      flush=True)
        for base, summ in res["collections"][coll.name]["baselines"].items():
            print(f"{name:14s} {'k':11s} {base:7s} purity {summ['summary']['purity']['mean']:.3f}")
    print("\n| collection | mode | " + " | ".join(FUSIONS) + " |")
    print("|---|---|" + "---|" * len(FUSIONS))
    for name in args.collections:
        for mode in args.modes:
            vals = {f: (m, s) for n, md, f, m, s in rows if n == name and md == mode}
            print(f"| {name} | {mode} | " + " | ".join(f"{vals[f][0]:.3f} ± {vals[f][1]:.3f}"
                                                     for f in FUSIONS) + " |")


if __name__ == "__main__":
    main()
