"""`python -m style_coanalysis <command>`: argument parsing and exit codes, nothing else.

Each command is implemented in the Blender adapter (`style_coanalysis.blender.cmd_<name>.run`),
imported only when that command runs, so `--help` and the pure core work without `bpy`.
Exit codes: 0 success, 2 bad input (message names the file or object), 1 internal error,
130 interrupted (Ctrl-C).
"""
from __future__ import annotations

import argparse
import importlib
import sys
import traceback

from .meshes import InputError
from .options import DEFAULTS, METHOD_HELP, METHODS, PARAMETERS, default, help_text


def _add_drawing_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--renderer", choices=("freestyle", "lineart", "zbuffer"), default="freestyle",
                   help="line renderer: freestyle (faithful, default), lineart (fast) or zbuffer "
                        "(fastest: depth buffers in numpy, no render engine)")
    p.add_argument("--up", choices=("z", "y"), default="z", help="up axis of the assets (default z)")
    p.add_argument("--collection", help="with a .blend INPUT: analyse only this collection's meshes")
    p.add_argument("--jobs", type=int, default=0,
                   help="parallel processes for per-shape work (default 0: all cores)")
    p.add_argument("--cache", help="cache folder of drawings, HOG maps, analyses, style regions "
                   "and synthetic dictionaries (default: style_coanalysis under the user cache)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="draw the shapes on the Dask cluster of this scheduler (tcp://host:8786; "
                        "needs dask[distributed], see README) instead of --jobs local processes")
    p.add_argument("--suggestive-contours", action="store_true",
                   help="also draw suggestive contours (paper's choice; freestyle only; slower, "
                        "see README)")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m style_coanalysis",
                                     description="Style co-analysis of 3D shapes from projected lines.")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("sample", help="generate the sample furniture collection with ground truth")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--size", type=int, default=120, help="number of shapes (default 120)")
    p.add_argument("--seed", type=int, default=0)

    p = sub.add_parser("render", help="render each shape's 12 line drawings as PNG")
    p.add_argument("input", help="a .blend file or a folder of mesh files (OBJ, PLY, STL, glTF)")
    p.add_argument("--out", required=True)
    _add_drawing_options(p)

    p = sub.add_parser("analyze", help="cluster shapes by style and mark their style regions")
    p.add_argument("input", help="a .blend file or a folder of mesh files (OBJ, PLY, STL, glTF)")
    p.add_argument("--out", required=True)
    _add_drawing_options(p)
    p.add_argument("--labels", help="CSV of name,style for a few shapes (semi-supervised)")
    p.add_argument("--triplets", help="CSV of a,b,c: a is closer in style to b than to c")
    p.add_argument("--clusters", default="auto",
                   help="'auto' or a number of style clusters, at least 2 and at most the "
                   "number of shapes; with --labels, the number of labelled styles (default auto)")
    p.add_argument("--method", choices=METHODS, default=None, help=f"{METHOD_HELP} (default "
                   f"{DEFAULTS.method})")
    p.add_argument("--seed", type=int, default=0, help="every random choice (default 0)")
    for option in PARAMETERS:   # defaults and help from params.AnalysisParams (one place)
        kind = type(default(option))
        p.add_argument(f"--{option}", type=kind, default=None, help=help_text(option))

    p = sub.add_parser("similar", help="rank the analysed shapes by style distance to one of them")
    p.add_argument("result", help="the --out folder of an analyze run")
    p.add_argument("name", nargs="?", help="the shape to rank the others against")
    p.add_argument("--top", type=int, default=10, help="how many to list (default 10)")
    p.add_argument("--triplets", help="CSV of a,b,c held out from the analysis: print the share "
                   "the style distance gets right (a closer to b than to c)")

    p = sub.add_parser("suggest-labels", help="which unlabelled shapes to label next")
    p.add_argument("result", help="the --out folder of an analyze run")
    p.add_argument("--n", type=int, default=5, help="how many shapes to suggest (default 5)")
    p.add_argument("--out", help="CSV to write (default: standard output); name,style rows with "
                   "the style left empty for you to fill in, then pass it to analyze --labels")

    p = sub.add_parser("identify", help="the style of each shape from labelled 2D line drawings")
    p.add_argument("input", help="a .blend file or a folder of mesh files (OBJ, PLY, STL, glTF)")
    p.add_argument("--drawings", required=True, help="folder with one subfolder of drawings per "
                   "style (PNG or JPEG, any size, dark lines on light or light on dark)")
    p.add_argument("--out", required=True, help="folder for identify.csv and identify.json")
    _add_drawing_options(p)
    p.add_argument("--seed", type=int, default=0, help="every random choice (default 0)")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        module = importlib.import_module(f".blender.cmd_{args.command.replace('-', '_')}",
                                         package=__package__)
        return int(module.run(args) or 0)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except Exception:  # an internal error: keep the traceback for the bug report
        traceback.print_exc()
        return 1
