"""The analysis' rounds under 1, 2 and 4 threads: seconds, and whether the partition is the same.

    nice -n 10 .venv/bin/python bench/bench_threads.py [--sizes 120 3000] [--threads 1 2 4]
        [--modes k auto labels-10% labels-20% triplets-300] [--seed 0]

A user's machine has its own number of cores, and the analysis must give the same partition on
any of them, as fast as the cores allow. For each size: N distinct copies of the benchmark's
sample-120 drawings (`bench_scale.Copies`: mirrored, shifted), their HOG maps and one encoding
(on every core), then `pipeline.analyse` on that encoding in every mode under each thread count
(`threadpoolctl`; more threads than cores is what a busy machine looks like). Labels and
triplets come from the copies' styles as the generalisation benchmark draws them. Prints the
seconds per thread count, their ratio to the first, and whether every partition equals the
first thread count's. Figures are ratios within one run (the machine is shared). Asserts
nothing.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

ROOT = Path(__file__).resolve().parent
sys.path[:0] = [str(ROOT.parent), str(ROOT)]

from bench_scale import Copies  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[120, 3000])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2, 4])
    ap.add_argument("--modes", nargs="+",
                    default=["k", "auto", "labels-10%", "labels-20%", "triplets-300"])
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()

    from style_coanalysis import pipeline
    from style_coanalysis.evaluation import benchmark as B
    from style_coanalysis.features import MapStore, hog_images
    from style_coanalysis.metrics import ari
    from style_coanalysis.params import AnalysisParams

    coll = B.load_collection("sample-120", log=lambda m: None)
    base_styles = list(coll.truth["style"])
    print(f"{'N':>5s} {'mode':13s} " + " ".join(f"{f'{t} thr s':>9s}" for t in args.threads)
          + "  " + " ".join(f"{f'{t}/{args.threads[0]}':>6s}" for t in args.threads[1:])
          + "  same partition", flush=True)
    for size in args.sizes:
        drawings = Copies(coll.drawings, size)
        names = [drawings[i].name for i in range(size)]
        styles = [base_styles[i % len(base_styles)] for i in range(size)]
        maps = MapStore()
        for i in range(size):
            maps.append(hog_images(drawings[i].images))
        t = time.perf_counter()
        encoded = pipeline.encode(drawings, AnalysisParams(random_state=args.seed), maps=maps)
        print(f"{size:5d} encoding {time.perf_counter() - t:.1f} s", flush=True)
        for mode in args.modes:
            k, labels, triplets, _ = B.constraints_for(mode, styles, names, args.seed)
            params = AnalysisParams(n_clusters=k, random_state=args.seed)
            seconds, parts = [], []
            for threads in args.threads:
                with threadpool_limits(limits=threads):
                    t = time.perf_counter()
                    r = pipeline.analyse(drawings, params, labels=labels, triplets=triplets,
                                         maps=maps, encoded=encoded)
                    seconds.append(time.perf_counter() - t)
                parts.append(np.asarray(r.clusters))
            same = [np.array_equal(parts[0], p) for p in parts[1:]]
            print(f"{size:5d} {mode:13s} " + " ".join(f"{s:9.1f}" for s in seconds) + "  "
                  + " ".join(f"{s / seconds[0]:6.2f}" for s in seconds[1:]) + "  "
                  + ("yes" if all(same) else "NO (ARI " + ", ".join(
                      f"{ari(parts[0], p):.3f}" for p in parts[1:]) + ")"), flush=True)
        maps.close()


if __name__ == "__main__":
    main()
