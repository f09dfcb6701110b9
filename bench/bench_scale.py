"""Whole-job scale benchmark: seconds per stage, seconds per shape, peak memory (issue 15).

    nice -n 10 .venv/bin/python bench/bench_scale.py [--sizes 120 500 1050]
        [--renderers lineart freestyle] [--jobs 1 2] [--analysis-sizes 120 1050 5000]
        [--work /tmp/sca_scale]

Part 1, the whole headless job (`job.run_steps`: draw, HOG, analyse, localise) on the first N
shapes of the sample collection, per renderer and number of jobs, from an empty cache; then once
more on the same shapes, which reads the drawings, HOG maps and analysis the first run cached
(the cache's worth: the second run over the first, goal under 0.10). Part 2, the
analysis alone, without Blender: the drawings of the benchmark's sample-120 made into N distinct
shapes (each copy mirrored and shifted by a few pixels, so no two are alike and the graph is not
120 cliques), generated one at a time as the analysis reads them, to see how HOG, encoding
(patches, dictionaries, word profiles), fusion, clustering and style regions grow with N. Regions
of a copy use the original's mesh and cameras (the cost is what is measured, not where they lie).

Each measurement runs in a fresh process, so its peak memory (the largest resident set of the
process and of its drawing workers) is its own; a process that grows past --mem-limit-gb is
stopped (this machine is shared) and reported as such. Figures are ratios within one run of
this script: the machine is shared, absolute seconds are noisy. Asserts nothing.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import replace

import numpy as np
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

STAGES = ("render", "hog", "analyse", "localise")
ANALYSIS_STAGES = ("hog", "encoding", "fusion", "clustering", "regions")


# ---------------------------------------------------------------- one measurement (a child)
def sample_meshes(size: int):
    """The first `size` shapes of the sample collection."""
    from style_coanalysis import sample
    return sample.generate(size=size, seed=0)


class Copies:
    """`size` distinct shapes made from a collection's drawings: copy j of drawing i is drawing
    i mirrored (odd copies) and shifted by a few whole pixels, seeds moved with the ink. Made on
    access, never held: a sequence the analysis reads one shape at a time."""

    SHIFTS = [(dy, dx) for r in range(4) for dy in range(-r, r + 1) for dx in range(-r, r + 1)
              if max(abs(dy), abs(dx)) == r]

    def __init__(self, drawings, size: int):
        self.base, self.size = drawings, size

    def __len__(self) -> int:
        return self.size

    def __getitem__(self, j: int):
        if not 0 <= j < self.size:
            raise IndexError(j)
        d = self.base[j % len(self.base)]
        copy = j // len(self.base)
        if copy == 0:
            return d
        dy, dx = self.SHIFTS[(copy // 2) % len(self.SHIFTS)]
        img = d.images[:, :, ::-1] if copy % 2 else d.images
        img = np.roll(img, (dy, dx), axis=(1, 2))
        px = d.seed_pixels.copy()
        if copy % 2:
            px[..., 0] = img.shape[2] - px[..., 0]
        px += np.array([dx, dy], np.float32)
        return replace(d, name=f"{d.name}~{copy}", images=np.ascontiguousarray(img),
                       seed_pixels=px)


def measure_analysis(size: int) -> dict:
    """HOG, encoding, fusion, clustering and regions of `size` copies of sample-120, one shape
    at a time; peak memory after each stage (the process' largest resident set so far)."""
    from style_coanalysis import localisation, pipeline
    from style_coanalysis.evaluation import benchmark as B
    from style_coanalysis.features import MapStore, hog_images
    from style_coanalysis.meshes import normalise
    from style_coanalysis.options import build_options
    coll = B.load_collection("sample-120", log=lambda m: None)
    base_meshes = [normalise(m) for m in coll.meshes]
    drawings = Copies(coll.drawings, size)
    del coll.maps
    options = build_options()
    params = options.params
    seconds, peak = {}, {}
    t = time.perf_counter()
    maps = MapStore()
    for i in range(size):
        maps.append(hog_images(drawings[i].images))
    seconds["hog"], peak["hog"] = time.perf_counter() - t, peak_rss_mb()
    t = time.perf_counter()
    enc = pipeline.encode(drawings, params, maps=maps)
    seconds["encoding"], peak["encoding"] = time.perf_counter() - t, peak_rss_mb()
    result = pipeline.analyse(drawings, params, maps=maps, encoded=enc)
    seconds["fusion"] = result.timings["fuse"]
    seconds["clustering"] = result.timings["cluster"] + result.timings["reselect"]
    peak["clustering"] = peak_rss_mb()
    t = time.perf_counter()
    marked = localisation.top_words(result.word_cluster, result.word_score,
                                    options.localisation.words_per_cluster)
    for i in range(size):
        m = base_meshes[i % len(base_meshes)]
        localisation.localise_shape(drawings[i], m.vertices, m.faces, result.words, marked,
                                    int(result.clusters[i]), params.patch_size,
                                    options.localisation.match_threshold, maps=maps[i])
    seconds["regions"], peak["regions"] = time.perf_counter() - t, peak_rss_mb()
    maps.close()
    return {"size": size, "seconds": seconds, "peak_mb": peak, "n_clusters": result.n_clusters,
            "rounds": len(result.rounds)}


def peak_rss_mb() -> float:
    """Largest resident set of this process and of any child it waited for (Linux: KiB)."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return max(own, kids) / 1024.0


def measure(size: int, renderer: str, jobs: int, cache: str) -> dict:
    import bpy
    from style_coanalysis.blender.job import run_steps
    from style_coanalysis.options import build_options
    bpy.ops.wm.read_factory_settings(use_empty=True)
    meshes = sample_meshes(size)
    options = build_options(jobs=jobs, cache_dir=cache)
    options = replace(options, renderer=renderer)    # also a renderer options.py does not list yet
    t0 = time.perf_counter()
    steps = run_steps(meshes, options)
    while True:
        try:
            next(steps)
        except StopIteration as stop:
            job = stop.value
            break
    wall = time.perf_counter() - t0
    seconds = job.report["seconds"]
    scores = job.report.get("scores", {}).get("style", {})
    return {"size": size, "renderer": renderer, "jobs": jobs,
            "wall": wall, "seconds": {k: seconds.get(k, 0.0) for k in STAGES},
            "shapes": len(job.shapes), "skipped": len(job.skipped),
            "purity": scores.get("purity"), "peak_mb": peak_rss_mb()}


# ---------------------------------------------------------------- the parent
def run_child(args: list[str], mem_limit_gb: float) -> dict:
    """Run one measurement in a fresh process; stop its process tree past the memory limit."""
    import psutil
    proc = subprocess.Popen([sys.executable, __file__, "_one", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    over = threading.Event()

    def watch():
        p = psutil.Process(proc.pid)
        while proc.poll() is None:
            try:
                rss = sum(q.memory_info().rss for q in [p, *p.children(recursive=True)])
            except psutil.Error:
                rss = 0
            if rss > mem_limit_gb * 2 ** 30:
                over.set()
                for q in [*p.children(recursive=True), p]:
                    try:
                        q.kill()
                    except psutil.Error:
                        pass
                return
            time.sleep(0.5)
    threading.Thread(target=watch, daemon=True).start()
    out, err = proc.communicate()
    if over.is_set():
        return {"error": f"stopped above {mem_limit_gb:g} GB"}
    lines = [line for line in out.splitlines() if line.startswith("RESULT ")]
    if proc.returncode != 0 or not lines:
        tail = (err.strip().splitlines() or [""])[-1]
        return {"error": f"exit code {proc.returncode}: {tail[:200]}"}
    return json.loads(lines[-1][7:])


def row(label: str, r: dict) -> str:
    if "error" in r:
        return f"{label:34s} {r['error']}"
    s = r["seconds"]
    per = r["wall"] / max(1, r["size"])
    return (f"{label:34s} {r['wall']:8.1f} " + " ".join(f"{s[k]:8.1f}" for k in STAGES)
            + f" {per:8.3f} {r['peak_mb']:8.0f}"
            + (f" {r['purity']:6.3f}" if r.get("purity") is not None else ""))


HEADER = (f"{'':34s} {'total s':>8s} " + " ".join(f"{k + ' s':>8s}" for k in STAGES)
          + f" {'s/shape':>8s} {'peak MB':>8s} {'purity':>6s}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[120, 500, 1050])
    ap.add_argument("--renderers", nargs="*", default=["lineart", "freestyle"])
    ap.add_argument("--jobs", type=int, nargs="*", default=[1, 2])
    ap.add_argument("--analysis-sizes", type=int, nargs="*", default=[120, 1050, 5000])
    ap.add_argument("--work", default=None, help="folder for the drawing caches (default: a "
                    "temporary folder, removed at the end)")
    ap.add_argument("--mem-limit-gb", type=float, default=12.0)
    ap.add_argument("--again", action=argparse.BooleanOptionalAction, default=True,
                    help="run each whole job a second time on the warm cache (default on)")
    args = ap.parse_args()
    work = Path(args.work or tempfile.mkdtemp(prefix="sca_scale_"))
    work.mkdir(parents=True, exist_ok=True)
    print(f"caches under {work}; {os.cpu_count()} cores", flush=True)

    if args.sizes:
        print("\n## The whole job from an empty cache, then again on the same shapes")
        print(HEADER)
        first = {}
        for size in args.sizes:
            for renderer in args.renderers:
                for jobs in args.jobs:
                    cache = work / f"cache-{renderer}-{size}-{jobs}"
                    a = ["--size", str(size), "--renderer", renderer, "--jobs", str(jobs),
                         "--cache", str(cache)]
                    r = run_child(a, args.mem_limit_gb)
                    first[size, renderer, jobs] = r
                    print(row(f"{size} {renderer} jobs={jobs}", r), flush=True)
                    if not args.again:
                        continue
                    again = run_child(a, args.mem_limit_gb)
                    print(row(f"{size} {renderer} jobs={jobs} again", again), flush=True)
                    if "error" not in r and "error" not in again:
                        print(f"{'':34s} second run / first: {again['wall'] / r['wall']:.2f}",
                              flush=True)
        print("\n## Ratios (the same run)")
        for size in args.sizes:
            for renderer in args.renderers:
                one, two = first.get((size, renderer, 1)), first.get((size, renderer, 2))
                if one and two and "error" not in one and "error" not in two:
                    print(f"{size} {renderer}: 2 jobs over 1 job, whole job "
                          f"{one['wall'] / two['wall']:.2f}x, drawing "
                          f"{one['seconds']['render'] / max(1e-9, two['seconds']['render']):.2f}x")
            if len(args.renderers) > 1:
                for jobs in args.jobs:
                    rs = {r: first.get((size, r, jobs)) for r in args.renderers}
                    if all(v and "error" not in v for v in rs.values()):
                        slow = max(rs, key=lambda k: rs[k]["seconds"]["render"])
                        for r, v in rs.items():
                            if r != slow:
                                print(f"{size} jobs={jobs}: drawing {slow} / {r} "
                                      f"{rs[slow]['seconds']['render'] / v['seconds']['render']:.1f}x"
                                      f", whole job {rs[slow]['wall'] / v['wall']:.1f}x")

    if args.analysis_sizes:
        print("\n## Analysis alone: copies of the benchmark's sample-120 drawings (mirrored, "
              "shifted), one shape at a time, no Blender")
        print(f"{'N':>6s} " + " ".join(f"{k + ' s':>13s}" for k in ANALYSIS_STAGES)
              + f" {'ms/shape':>9s} {'peak MB':>8s} {'k':>3s} {'rounds':>6s}")
        base = None
        for size in args.analysis_sizes:
            r = run_child(["--analysis", "--size", str(size)], args.mem_limit_gb)
            if "error" in r:
                print(f"{size:6d} {r['error']}", flush=True)
                continue
            s = r["seconds"]
            per = {k: 1000 * s[k] / size for k in ANALYSIS_STAGES}
            print(f"{size:6d} " + " ".join(f"{s[k]:13.1f}" for k in ANALYSIS_STAGES)
                  + f" {sum(per.values()):9.1f} {max(r['peak_mb'].values()):8.0f}"
                  + f" {r['n_clusters']:3d} {r['rounds']:6d}", flush=True)
            print(f"{'':6s} ms per shape: " + ", ".join(f"{k} {per[k]:.2f}" for k in per)
                  + "; peak MB after " + ", ".join(f"{k} {v:.0f}" for k, v in r["peak_mb"].items()),
                  flush=True)
            if base is None:
                base = per
            print(f"{'':6s} per shape vs N={args.analysis_sizes[0]}: " + ", ".join(
                f"{k} {per[k] / max(1e-9, base[k]):.2f}x" for k in per), flush=True)


def one() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("_one")
    ap.add_argument("--size", type=int, required=True)
    ap.add_argument("--renderer")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--cache")
    ap.add_argument("--analysis", action="store_true")
    a = ap.parse_args()
    r = measure_analysis(a.size) if a.analysis else measure(a.size, a.renderer, a.jobs, a.cache)
    print("RESULT " + json.dumps(r), flush=True)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "_one":
        one()
    else:
        main()
