"""`analyze INPUT --out DIR`: the product's main job, headless.

Loads the shapes (a .blend, or a folder of mesh files), checks every constraint before any work,
runs the job with progress on stderr, writes the results onto the objects and saves them as
DIR/result.blend (never over the input), then DIR/report.json and DIR/report.html.
"""
from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from .. import constraints, report
from ..meshes import InputError, normalise
from ..params import AnalysisParams
from . import scene
from .job import JobOptions, run_steps


def parse_clusters(text: str) -> int | None:
    if str(text).lower() == "auto":
        return None
    try:
        k = int(text)
    except ValueError:
        k = 0
    if k < 2:
        raise InputError(f"--clusters must be 'auto' or a whole number of at least 2, not '{text}'")
    return k


def load_input(path: str, collection: str | None):
    """Meshes from a .blend or a folder; the shapes' objects are then in the open session."""
    p = Path(path)
    if not p.exists():
        raise InputError(f"'{path}' does not exist")
    if p.is_dir():
        if collection:
            raise InputError("--collection applies to a .blend INPUT, not to a folder")
        import bpy
        bpy.ops.wm.read_factory_settings(use_empty=True)
        meshes = scene.import_mesh_files(p)
        # the shapes become objects of an empty scene: result.blend holds them with their results
        names = scene.objects_from_meshes(meshes, "Shapes")
        for m, name in zip(meshes, names):
            m.name = name
        return meshes
    if p.suffix.lower() == ".blend":
        return scene.meshes_from_blend(p, collection)
    raise InputError(f"'{path}' is neither a .blend file nor a folder of mesh files")


class StderrProgress:
    """One line per step on stderr: stage, i of n, elapsed, estimate for the stage."""

    def __init__(self, stream=sys.stderr):
        self.stream = stream
        self.start = time.perf_counter()
        self.stage_start = {}
        self.last = None

    def __call__(self, stage: str, done: int, total: int) -> None:
        if (stage, done) == self.last:
            return
        self.last = (stage, done)
        now = time.perf_counter()
        t0 = self.stage_start.setdefault(stage, now)
        eta = ""
        if 0 < done < total:
            eta = f", about {(now - t0) / done * (total - done):.0f} s left in this stage"
        self.stream.write(f"[{now - self.start:7.1f} s] {stage} {done}/{total}{eta}\n")
        self.stream.flush()


def run(args) -> int:
    import bpy

    clusters = parse_clusters(args.clusters)
    out = Path(args.out)
    meshes = load_input(args.input, args.collection)
    if not meshes:
        raise InputError(f"'{args.input}' contains no mesh")
    names = [m.name for m in meshes]
    labels = constraints.read_labels_csv(args.labels, names) if args.labels else None
    triplets = constraints.read_triplets_csv(args.triplets, names) if args.triplets else None
    if out.resolve() == Path(args.input).resolve():
        raise InputError("--out must not be the input itself")
    out.mkdir(parents=True, exist_ok=True)

    params = AnalysisParams(n_representatives=args.representatives, n_clusters=clusters,
                            eta=args.eta, lam=args.lam, beta=args.beta, gamma=args.gamma,
                            mu=args.mu, max_rounds=args.rounds, random_state=args.seed)
    options = JobOptions(renderer=args.renderer, up=args.up,
                         suggestive_contours=args.suggestive_contours,
                         jobs=args.jobs or (os.cpu_count() or 1), cache_dir=args.cache,
                         seed=args.seed, params=params, labels=labels, triplets=triplets)
    progress = StderrProgress()
    progress("load", len(meshes), len(meshes))
    steps = run_steps(meshes, options)
    while True:
        try:
            progress(*next(steps))
        except StopIteration as stop:
            job = stop.value
            break
    for name, reason in job.skipped:
        print(f"warning: skipped '{name}': {reason}", file=sys.stderr)

    from .writeback import write_results
    write_results(bpy.context.scene, job)
    bpy.ops.wm.save_as_mainfile(filepath=str((out / "result.blend").resolve()), copy=True)
    report.write_json(job.report, out / "report.json")
    by_name = {m.name: m for m in meshes}
    normalised = [normalise(by_name[s.name], args.up) for s in job.shapes]
    report.write_html(job, normalised, out)
    summary = f"{len(job.shapes)} shapes in {len(job.clusters)} clusters"
    if "scores" in job.report:
        s = job.report["scores"]["style"]
        summary += f"; style purity {s['purity']:.3f}, NMI {s['nmi']:.3f}"
    print(f"{summary}; wrote {out}/result.blend, report.json, report.html", file=sys.stderr)
    return 0
