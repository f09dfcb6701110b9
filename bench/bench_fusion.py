"""Which fusion of the default method's views holds across collections? (issue 11, item 3)

The default fuses its views (structure-relative words at every rung of the neighbour ladder, and
the line character) as graphs. This prints, for the same views, style purity (mean +- std over
seeds) with the fusion replaced by PSLF (paper eq. 1/2, its learned view weights), by
concatenation and by PCA of the concatenation, beside line statistics, on collections of
different sources and make-ups. Modes: k given, and 20% labels. Each seed's encoding is computed
once and shared by the fusions, so they differ in the fusion only.

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
    rows, lines = [], {}
    for name in args.collections:
        coll = B.load_collection(name)
        encoded = {}                  # one encoding per seed, shared by the fusions

        for fusion in FUSIONS:
            def run(d, p, lab, tri, maps, fusion=fusion):
                if p.random_state not in encoded:
                    encoded[p.random_state] = pipeline.encode(d, p, maps)
                return pipeline.analyse(d, p, labels=lab, triplets=tri, maps=maps, fusion=fusion,
                                        encoded=encoded[p.random_state])
            res = B.evaluate([coll], modes=args.modes, methods=["default"], seeds=args.seeds,
                             analyse_fn=run, stability=False)
            for mode in args.modes:
                s = res["collections"][coll.name]["modes"][mode]["default"]["summary"]["purity"]
                rows.append((name, mode, fusion, s["mean"], s["std"]))
                print(f"{name:14s} {mode:11s} {fusion:7s} purity {s['mean']:.3f} +- {s['std']:.3f}",
                      flush=True)
        summ = res["collections"][coll.name]["baselines"]["line statistics"]["summary"]
        lines[name] = summ["purity"]["mean"]
    print("\n| collection | mode | " + " | ".join(FUSIONS) + " | line statistics (k given) |")
    print("|---|---|" + "---|" * (len(FUSIONS) + 1))
    for mode in args.modes:
        for name in args.collections:
            vals = {f: (m, s) for n, md, f, m, s in rows if n == name and md == mode}
            print(f"| {name} | {mode} | " + " | ".join(f"{vals[f][0]:.3f} ± {vals[f][1]:.3f}"
                                                     for f in FUSIONS) + f" | {lines[name]:.3f} |")
        sums = {f: sum(m for n, md, ff, m, s in rows if md == mode and ff == f) for f in FUSIONS}
        print(f"| **sum** | {mode} | " + " | ".join(f"{sums[f]:.2f}" for f in FUSIONS) +
              f" | {sum(lines.values()):.2f} |")


if __name__ == "__main__":
    main()
