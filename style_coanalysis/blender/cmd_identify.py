"""`identify INPUT --drawings DIR --out DIR`: the style of each shape from labelled 2D drawings.

The drawings are read and checked first (a bad image is refused by name before any rendering),
then the shapes are drawn and analysed as `analyze` does (the analysis provides the word
dictionary both sides are encoded with, `identify.py`), and each shape's views vote. DIR gets
identify.csv (name, style, the votes per style) and identify.json, written into a temporary
folder that then replaces DIR whole (`options.publish`), like `analyze`.
"""
from __future__ import annotations

import csv
import io
import json
import os
import sys

from .. import identify as ident
from ..meshes import InputError
from ..options import PARAMETERS, build_options, check_output, publish

CSV_NAME, JSON_NAME = "identify.csv", "identify.json"


def identify_job(meshes, options, drawings: ident.DrawingSet, progress=None):
    """(JobResult, [Identification] in job.shapes order): the analysis, then the vote."""
    from dataclasses import replace

    from .job import run_steps
    # the vote reads only the word dictionary, made before the clustering rounds: one round
    options.params = replace(options.params, max_rounds=1)
    steps = run_steps(meshes, options)
    while True:
        try:
            step = next(steps)
            if progress is not None:
                progress(*step)
        except StopIteration as stop:
            job = stop.value
            break
    views = [d.images for d in job.drawings]
    return job, ident.identify(views, drawings, job.analysis.words)


def table(job, found, drawings: ident.DrawingSet) -> str:
    styles = sorted(set(drawings.styles))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["name", "style"] + [f"votes_{s}" for s in styles])
    for shape, r in zip(job.shapes, found):
        w.writerow([shape.name, r.style] + [r.votes[s] for s in styles])
    return buf.getvalue()


def run(args) -> int:
    from .cmd_analyze import StderrProgress, load_input
    options = build_options(
        renderer=args.renderer, up=args.up, suggestive_contours=args.suggestive_contours,
        jobs=args.jobs, cache_dir=args.cache, seed=args.seed, clusters="auto",
        **{option: None for option in PARAMETERS})
    options.jobs = options.jobs or (os.cpu_count() or 1)
    out = check_output(args.out, inputs=(args.input, args.drawings), cache_dir=args.cache)
    drawings = ident.load_drawings(args.drawings)          # every image checked before rendering
    progress = StderrProgress()
    progress("drawings", len(drawings.styles), len(drawings.styles))
    from . import batch
    with batch.use_scheduler(getattr(args, "scheduler", None)):
        meshes = load_input(args.input, args.collection)
        if not meshes:
            raise InputError(f"'{args.input}' contains no mesh")
        job, found = identify_job(meshes, options, drawings, progress)
    for name, reason in job.skipped:
        print(f"warning: skipped '{name}': {reason}", file=sys.stderr)

    def write(folder):
        (folder / CSV_NAME).write_text(table(job, found, drawings), encoding="utf-8")
        (folder / JSON_NAME).write_text(json.dumps({
            "drawings": [{"path": p, "style": s} for p, s in zip(drawings.paths, drawings.styles)],
            "shapes": [{"name": sh.name, "style": r.style, "votes": r.votes,
                        "nearest_drawing_per_view": [drawings.paths[j] for j in r.nearest]}
                       for sh, r in zip(job.shapes, found)],
            "skipped": [{"name": n, "reason": why} for n, why in job.skipped]}, indent=1))
    publish(out, write)
    print(f"{len(found)} shapes identified from {len(drawings.styles)} drawings of "
          f"{len(set(drawings.styles))} styles; wrote {out}/{CSV_NAME}", file=sys.stderr)
    return 0
