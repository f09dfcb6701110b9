"""`analyze INPUT --out DIR`: the product's main job, headless.

Checks every argument and the output folder (`options`), loads the shapes (a .blend, or a folder
of mesh files) and the constraint files, runs the job with progress on stderr, writes the results
onto the objects and saves DIR/result.blend, DIR/report.json, DIR/report.html and
DIR/style_space.npz (what the `similar` and `suggest-labels` commands read) into a temporary
folder beside DIR that then replaces DIR whole (`options.publish`): DIR holds a complete
previous result or the complete new one, and never an input.
"""
from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from .. import report
from ..meshes import InputError, normalise
from ..options import PARAMETERS, build_options, check_output, load_constraints, publish
from . import batch, scene
from .job import run_steps


def load_input(path: str, collection: str | None):
    """Meshes from a .blend or a folder; the shapes' objects are then in the open session."""
    p = Path(path)
    if not p.exists():
        raise InputError(f"'{path}' does not exist")
    if p.is_dir():
        if collection:
            raise InputError("--collection applies to a .blend INPUT, not to a folder")
        scene.empty_session()
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
    """Progress lines on stderr: stage, i of n, elapsed, estimate for the stage.

    A line when a stage starts or ends, and within a stage at most every `every` seconds, so a
    long stage (or a long shape, whose steps carry a detail such as its view) is never silent
    and a short one is not noisy."""

    def __init__(self, stream=sys.stderr, every: float = 1.0):
        self.stream = stream
        self.start = time.perf_counter()
        self.stage_start = {}
        self.last = None
        self.last_line = -1e9
        self.every = every

    def __call__(self, stage: str, done: int, total: int, detail: str | None = None) -> None:
        now = time.perf_counter()
        new_stage = self.last is None or self.last[0] != stage
        if not (new_stage or done == total and self.last != (stage, done)
                or now - self.last_line >= self.every):
            return
        self.last = (stage, done)
        t0 = self.stage_start.setdefault(stage, now)
        eta = ""
        if 0 < done < total:
            eta = f", about {(now - t0) / done * (total - done):.0f} s left in this stage"
        more = f" ({detail})" if detail else ""
        self.stream.write(f"[{now - self.start:7.1f} s] {stage} {done}/{total}{more}{eta}\n")
        self.stream.flush()
        self.last_line = now


def run(args) -> int:
    import bpy

    # 1. every argument and the output folder, before anything is loaded or rendered
    options = build_options(
        renderer=args.renderer, up=args.up, suggestive_contours=args.suggestive_contours,
        jobs=args.jobs, cache_dir=args.cache, seed=args.seed, clusters=args.clusters,
        method=args.method, labels=args.labels, triplets=args.triplets,
        **{option: getattr(args, option) for option in PARAMETERS})
    options.jobs = options.jobs or (os.cpu_count() or 1)
    out = check_output(args.out, inputs=(args.input, args.labels, args.triplets),
                       cache_dir=args.cache)
    # 2. the shapes and the constraint files that name them; the job checks the rest
    # (analysable shapes, cluster count) before its first render
    progress = StderrProgress()
    with batch.use_scheduler(getattr(args, "scheduler", None)):   # connects now: errors first
        meshes = load_input(args.input, args.collection)
        if not meshes:
            raise InputError(f"'{args.input}' contains no mesh")
        load_constraints(options, [m.name for m in meshes])
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

    # 3. results: written into a temporary folder beside --out, then moved into place whole
    def write(folder: Path) -> None:
        from ..similarity import SPACE_FILE
        from .space_store import write_scene
        from .writeback import write_results
        write_results(bpy.context.scene, job, progress=progress)
        write_scene(bpy.context.scene, job.style_space)   # for the later uses, in result.blend
        job.style_space.save(folder / SPACE_FILE)         # ... and for the headless commands
        progress("save result.blend", 0, 1)
        bpy.ops.wm.save_as_mainfile(filepath=str((folder / "result.blend").resolve()), copy=True)
        progress("save result.blend", 1, 1)
        report.write_json(job.report, folder / "report.json")
        by_name = {m.name: m for m in meshes}
        normalised = [normalise(by_name[s.name], args.up) for s in job.shapes]
        report.write_html(job, normalised, folder, progress=progress)

    publish(out, write)
    summary = f"{len(job.shapes)} shapes in {len(job.clusters)} clusters"
    if "scores" in job.report:
        s = job.report["scores"]["style"]
        summary += f"; style purity {s['purity']:.3f}, NMI {s['nmi']:.3f}"
    print(f"{summary}; wrote {out}/result.blend, report.json, report.html", file=sys.stderr)
    for level, note in report.run_notes(job.report):
        print(f"{'warning: ' if level == 'WARNING' else ''}{note}", file=sys.stderr)
    return 0
