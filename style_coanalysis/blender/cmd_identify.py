"""`identify INPUT --drawings DIR --out DIR`: the style of each shape from labelled 2D drawings.

The drawings are read and checked first (a bad image is refused by name before any rendering),
then the shapes are drawn and analysed as `analyze` does (the analysis provides the word
dictionary both sides are encoded with, `identify.py`), each shape's views vote, and the windows
matching the words characteristic of the winning style are back-projected as its style regions.
DIR gets identify.csv (name, style, the votes per style) and identify.json (with, per shape, its
regions' vertex and face weights), written into a temporary folder that then replaces DIR whole
(`options.publish`), like `analyze`.
"""
from __future__ import annotations

import csv
import io
import json
import os
import sys
from dataclasses import dataclass

import numpy as np

from .. import identify as ident
from ..meshes import InputError, face_areas, normalise
from ..options import PARAMETERS, build_options, check_output, publish

CSV_NAME, JSON_NAME = "identify.csv", "identify.json"


@dataclass
class IdentifyRun:
    job: object               # the analysis' JobResult (job.shapes: the identified shapes)
    found: list               # Identification per shape, job.shapes order
    regions: list             # localisation.ShapeLocalisation of the identified style, same order
    word_style: np.ndarray    # (K,) style index (into styles) of each characteristic word, -1 else
    styles: list              # sorted style names


def identify_job(meshes, options, drawings: ident.DrawingSet, progress=None) -> IdentifyRun:
    """The analysis, the vote, then each shape's identified style regions."""
    from dataclasses import replace

    from .job import run_steps
    # the vote reads only the (first) word dictionary, made before the clustering rounds: one
    # round, one dictionary
    options.params = replace(options.params, max_rounds=1, n_dictionaries=1)
    steps = run_steps(meshes, options)
    while True:
        try:
            step = next(steps)
            if progress is not None:
                progress(*step)
        except StopIteration as stop:
            job = stop.value
            break
    by_name = {m.name: m for m in meshes}
    normal = (normalise(by_name[s.name], options.up) for s in job.shapes)   # one at a time
    found, regions, word_style, styles = ident.identify_shapes(
        job.drawings, normal, drawings, job.analysis.words, options.localisation.words_per_cluster,
        options.params.patch_size, options.localisation.match_threshold, progress)
    return IdentifyRun(job, found, regions, word_style, styles)


def rounded(weights) -> np.ndarray:
    """Weights as identify.json holds them (4 decimals)."""
    return np.round(np.asarray(weights, np.float64), 4)


def region_summary(run: IdentifyRun, meshes, options) -> list:
    """Per shape: style-region faces (weight > 0.5) and their share of the surface area (in the
    normalised frame, so the figure does not depend on the file's unit)."""
    by_name = {m.name: m for m in meshes}
    out = []
    for shape, loc in zip(run.job.shapes, run.regions):
        m = normalise(by_name[shape.name], options.up)
        inside = rounded(loc.face_weights) > 0.5       # counted on the weights as written
        area = face_areas(m.vertices, m.faces)
        out.append({"faces": int(inside.sum()),
                    "area_share": round(float(area[inside].sum() / max(area.sum(), 1e-30)), 4),
                    "best_view": int(loc.best_view)})
    return out


def table(job, found, drawings: ident.DrawingSet) -> str:
    styles = sorted(set(drawings.styles))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["name", "style"] + [f"votes_{s}" for s in styles])
    for shape, r in zip(job.shapes, found):
        w.writerow([shape.name, r.style] + [r.votes[s] for s in styles])
    return buf.getvalue()


def json_text(run: IdentifyRun, drawings: ident.DrawingSet, summary: list) -> str:
    """identify.json: indented, except `region_weights`, one compact line per shape (thousands of
    numbers each). The weights live here, not in a file of their own, because a later run may
    replace --out only when it holds nothing but result entries (options.RESULT_ENTRIES)."""
    job, found = run.job, run.found
    head = json.dumps({
        "drawings": [{"path": p, "style": s} for p, s in zip(drawings.paths, drawings.styles)],
        "characteristic_words": {s: np.flatnonzero(run.word_style == k).tolist()
                                 for k, s in enumerate(run.styles)},
        "shapes": [{"name": sh.name, "style": r.style, "votes": r.votes,
                    "nearest_drawing_per_view": [drawings.paths[j] for j in r.nearest],
                    "region": reg}
                   for sh, r, reg in zip(job.shapes, found, summary)],
        "skipped": [{"name": n, "reason": why} for n, why in job.skipped],
        "region_weights_note": "per shape, in 'shapes' order: 'vertex' in the object's vertex "
                               "order, 'face' per triangle; > 0.5: style region"}, indent=1)
    rows = [json.dumps({"name": sh.name,
                        "vertex": rounded(loc.weights).tolist(),
                        "face": rounded(loc.face_weights).tolist()},
                       separators=(",", ":"))
            for sh, loc in zip(job.shapes, run.regions)]
    assert head.endswith("\n}")
    return head[:-2] + ',\n "region_weights": [\n  ' + ",\n  ".join(rows) + "\n ]\n}\n"


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
        run = identify_job(meshes, options, drawings, progress)
    job, found = run.job, run.found
    summary = region_summary(run, meshes, options)
    for name, reason in job.skipped:
        print(f"warning: skipped '{name}': {reason}", file=sys.stderr)

    def write(folder):
        (folder / CSV_NAME).write_text(table(job, found, drawings), encoding="utf-8")
        (folder / JSON_NAME).write_text(json_text(run, drawings, summary), encoding="utf-8")
    publish(out, write)
    print(f"{len(found)} shapes identified from {len(drawings.styles)} drawings of "
          f"{len(set(drawings.styles))} styles; wrote {out}/{CSV_NAME}", file=sys.stderr)
    return 0
