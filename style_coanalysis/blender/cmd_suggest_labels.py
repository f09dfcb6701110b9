"""`suggest-labels RESULT_DIR [--n 5] [--out CSV]`: which shapes to label next, as a labels CSV.

The CSV is `name,style` with the style left empty and each shape's reason in a comment line
above it: fill in the styles and pass the file to `analyze --labels` (it refuses an empty style,
naming the line). Written to standard output, or to --out through a temporary file and a rename.
Reads only RESULT_DIR/style_space.npz; --out may not lie inside RESULT_DIR, which the next
`analyze` replaces whole (and it refuses --labels inside its --out).
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

from .. import atomic
from ..meshes import InputError
from ..similarity import StyleSpace
from ..suggest import suggest


def to_csv(picks) -> str:
    lines = ["# suggested by suggest-labels: fill in each style, then use as analyze --labels",
             "name,style"]
    for k, p in enumerate(picks, start=1):
        lines += [f"# {k}. {p.name}: {p.reason}", f"{p.name},"]
    return "\n".join(lines) + "\n"


def run(args) -> int:
    if args.n < 1:
        raise InputError(f"--n must be at least 1, got {args.n}")
    out = None
    if args.out:
        out = Path(os.path.abspath(args.out))
        result = Path(os.path.abspath(args.result))
        if out == result or result in out.parents:
            raise InputError(f"--out '{out}' is inside the result folder '{result}', which the "
                             "next analyze replaces whole: write it elsewhere")
        if out.is_dir():
            raise InputError(f"--out '{out}' is a folder, give a CSV file name")
        if not out.parent.is_dir():
            raise InputError(f"--out '{out}': the folder '{out.parent}' does not exist")
    space = StyleSpace.load(args.result)
    text = to_csv(suggest(space, args.n))
    if out is None:
        sys.stdout.write(text)
        return 0
    atomic.write_text(out, text)
    print(f"wrote {out}", file=sys.stderr)
    return 0
