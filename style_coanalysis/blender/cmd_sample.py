"""`python -m style_coanalysis sample --out DIR`: write the sample collection with its ground truth.

Outputs, so every consumer finds what it reads: DIR/sample.blend (one object per shape, laid out
on a grid, truth as custom properties and the 'style_truth' face attribute), DIR/meshes/<name>.obj
(shape coordinates, standing at the origin), DIR/truth/<name>.npz and DIR/labels.csv.
"""
from __future__ import annotations

import csv
import os
import sys
import time

from .. import meshio, sample
from ..meshes import InputError, validate
from . import scene


def run(args) -> int:
    if args.size < 1:
        raise InputError(f"--size must be at least 1 (got {args.size})")
    out = os.path.abspath(args.out)
    if os.path.exists(out) and not os.path.isdir(out):
        raise InputError(f"{out}: exists and is not a folder")
    t0 = time.time()
    shapes = sample.generate(size=args.size, seed=args.seed)
    for m in shapes:
        validate(m)
    print(f"generated {len(shapes)} shapes in {time.time() - t0:.1f} s", file=sys.stderr)

    os.makedirs(os.path.join(out, "meshes"), exist_ok=True)
    os.makedirs(os.path.join(out, "truth"), exist_ok=True)
    with open(os.path.join(out, "labels.csv"), "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["name", "style", "category"])
        for i, m in enumerate(shapes):
            meshio.write_obj(m, os.path.join(out, "meshes", f"{m.name}.obj"))
            meshio.write_truth(m, os.path.join(out, "truth", f"{m.name}.npz"))
            w.writerow([m.name, m.truth["style"], m.truth["category"]])
            if (i + 1) % 20 == 0 or i + 1 == len(shapes):
                print(f"wrote {i + 1}/{len(shapes)} OBJ + truth files", file=sys.stderr)

    names = scene.write_blend(shapes, os.path.join(out, "sample.blend"), "Sample")
    print(f"saved {os.path.join(out, 'sample.blend')} ({len(names)} objects) "
          f"in {time.time() - t0:.1f} s", file=sys.stderr)
    return 0
