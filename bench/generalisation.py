"""The generalisation benchmark of issue 11: does the analysis find style on collections it was not
tuned on, beside trivial baselines and the paper's method, and is it stable?

    python bench/generalisation.py --quick --seeds 3        # a few minutes once drawings are cached
    python bench/generalisation.py                          # every collection, mode and method
    python bench/generalisation.py --collections sample hu2017-60 --modes k auto --methods default
    python bench/generalisation.py --table bench/results/generalisation.json   # reprint a table
    python bench/generalisation.py --table old.json new.json   # one table of several runs
    python bench/generalisation.py @bench/results/table.args --goals   # the README's table

Collections, modes and the scoring loop live in `style_coanalysis/evaluation/benchmark.py`
(importable: `load_collection`, `evaluate`, `summary_table`). Writes
bench/results/generalisation[_quick].json (every number) and .png (per collection: style purity of
the default and paper methods per mode, std bars, baselines and chance as lines); prints the
Markdown table to stdout and progress to stderr. Drawings come from the user cache
(~/.cache/style_coanalysis); shapes not cached yet are rendered (about 1 s per shape per core).
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from style_coanalysis.evaluation import benchmark as B  # noqa: E402

RESULTS = ROOT / "bench" / "results"


def code_state() -> dict:
    """The commit the analysis code was imported from, and whether its files differed from it
    (others edit the tree while a long run goes on: a result belongs to the code it ran)."""
    import subprocess

    def git(*a):
        try:
            return subprocess.run(["git", *a], cwd=ROOT, capture_output=True, text=True,
                                  timeout=30).stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return ""
    dirty = git("status", "--porcelain", "--", "style_coanalysis").splitlines()
    return {"commit": git("rev-parse", "--short", "HEAD"), "uncommitted": dirty,
            "started": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
            "kernels": kernels()}


def kernels() -> list[str]:
    """The numeric kernels this machine picked: OpenBLAS's (by processor) and whether numpy
    runs its AVX-512 ones. A result can depend on them: the synthetic words of analysis seeds
    other than the default's (which ship with the package) are computed by a k-means that
    OpenBLAS's Haswell and SkylakeX kernels end differently on 2 of seed 2's 10 dictionaries
    (docs/generalisation.md, "The same shapes on other machines")."""
    from threadpoolctl import threadpool_info
    out = sorted({f"{i['internal_api']} {i.get('version')} {i.get('architecture')}"
                  for i in threadpool_info() if i.get("user_api") == "blas"})
    try:
        from numpy.core._multiarray_umath import __cpu_features__
        out.append("numpy AVX-512 " + ("on" if __cpu_features__.get("AVX512F") else "off"))
    except ImportError:
        pass
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 fromfile_prefix_chars="@")
    ap.add_argument("--collections", nargs="+", default=None,
                    help="names or prefixes (default: all): " + ", ".join(B.collection_specs()))
    ap.add_argument("--modes", nargs="+", default=None, choices=B.MODES, metavar="MODE",
                    help="default: all: " + ", ".join(B.MODES).replace("%", "%%"))
    ap.add_argument("--methods", nargs="+", default=None, choices=B.METHODS, help="default: both")
    ap.add_argument("--seeds", type=int, default=3, help="seeds 0..N-1 (label/triplet draw and "
                    "random_state)")
    ap.add_argument("--jobs", type=int, default=0, help="render processes (0: all cores)")
    ap.add_argument("--quick", action="store_true",
                    help=f"collections {', '.join(B.QUICK_COLLECTIONS)}; modes "
                         f"{', '.join(B.QUICK_MODES)}; render-based stability on sample-120 only".replace("%", "%%"))
    ap.add_argument("--no-stability", action="store_true", help="skip every stability check")
    ap.add_argument("--stability-everywhere", action="store_true",
                    help="render-based stability (scaled, OBJ, .blend, turned) on every collection, "
                         f"not only {', '.join(B.RENDER_STABILITY_DEFAULT)}")
    ap.add_argument("--stability-seeds", type=int, default=1,
                    help="stability over the first N seeds (each variant: one analysis per mode "
                         "and seed)")
    ap.add_argument("--stability-modes", nargs="+", default=list(B.STABILITY_MODES),
                    choices=B.MODES, metavar="MODE",
                    help="the modes whose partitions the stability checks compare (default: "
                    + " ".join(B.STABILITY_MODES) + "; with labels or triplets every variant "
                    "gets the same ones)")
    ap.add_argument("--renderer", default=B.DRAWING_SETTINGS.renderer,
                    choices=("freestyle", "lineart", "zbuffer"),
                    help="what draws the collections (default %(default)s)")
    ap.add_argument("--out", default=None, help="output stem under bench/results "
                    "(default generalisation, generalisation_quick with --quick)")
    ap.add_argument("--table", metavar="JSON", nargs="+", default=None,
                    help="only print the Markdown table of saved results (e.g. partial runs); "
                         "with several files, a method's figures in a later file replace the "
                         "same collection and mode of an earlier one measured on no more seeds; "
                         "@FILE reads arguments from FILE, one a line (bench/results/table.args "
                         "lists the README table's files)")
    ap.add_argument("--goals", action="store_true",
                    help="with --table: also print issue 11's goals read off the results")
    args = ap.parse_args(argv)
    if args.table:
        merged = B.merge_results([json.loads(Path(f).read_text()) for f in args.table])
        print(B.summary_table(merged))
        if args.goals:
            print("\n" + B.goal_report(merged))
        return 0

    collections = B.select_collections(args.collections or (B.QUICK_COLLECTIONS if args.quick else None))
    modes = args.modes or (list(B.QUICK_MODES) if args.quick else list(B.MODES))
    methods = args.methods or list(B.METHODS)
    render = True if args.stability_everywhere else (
        ("sample-120",) if args.quick else B.RENDER_STABILITY_DEFAULT)
    t0 = time.perf_counter()
    print(f"collections: {', '.join(collections)}\nmodes: {', '.join(modes)}; methods: "
          f"{', '.join(methods)}; seeds: {args.seeds}", file=sys.stderr)
    command = " ".join(["python bench/generalisation.py"] + list(argv or sys.argv[1:]))
    RESULTS.mkdir(parents=True, exist_ok=True)
    stem = args.out or ("generalisation_quick" if args.quick else "generalisation")

    code = code_state()

    def save(results, complete=False):
        results["command"] = command
        results["code"] = code
        results["complete"] = complete
        results["wall_seconds"] = time.perf_counter() - t0
        (RESULTS / f"{stem}.json").write_text(json.dumps(B.to_json(results), indent=1))
        B.plot(results, RESULTS / f"{stem}.png")

    # saved after every collection, so a long run that is stopped keeps what it measured
    results = B.evaluate(collections, modes, methods, args.seeds, stability=not args.no_stability,
                         render_stability=render, stability_seeds=args.stability_seeds,
                         stability_modes=args.stability_modes,
                         jobs=args.jobs, on_collection=save, renderer=args.renderer)
    save(results, complete=True)
    print(B.summary_table(results))
    print(f"\ncode {code['commit']} ({len(code['uncommitted'])} uncommitted files under "
          f"style_coanalysis/ at the start); kernels: {'; '.join(code['kernels'])}",
          file=sys.stderr)
    print(f"\n`{command}`: {results['wall_seconds'] / 60:.1f} min; "
          f"wrote {RESULTS / stem}.json and .png", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
