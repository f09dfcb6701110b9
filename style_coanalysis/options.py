"""A run's options, built and checked in one place before any work starts.

The headless command (`blender/cmd_analyze.py`) and the panel's operator (`operators/analyse.py`)
both call `build_options` with the raw values a person gave; it fills every value left out from
`params.AnalysisParams`' defaults (the paper's values live only there), checks each one and
raises `InputError` naming the option and the problem. `check_shapes` then checks what needs the
loaded shapes (cluster count, names in the constraints) and `check_output` the command's output
folder, all before the first render. Pure Python: no bpy.
"""
from __future__ import annotations

import csv
import math
import os
import tempfile
from dataclasses import dataclass, field, fields
from pathlib import Path

from .meshes import InputError
from .params import AnalysisParams, DrawingSettings, LocalisationParams

RENDERERS = ("freestyle", "lineart", "zbuffer")
UP_AXES = ("z", "y")
METHODS = ("default", "paper")
DEFAULTS = AnalysisParams()              # the paper's values, read from params.py only

# The analysis parameters a person may set: option name -> (AnalysisParams field, help text).
# The command's flags (--representatives, ...) and the panel's Advanced properties use these.
PARAMETERS = {
    "representatives": ("n_representatives", "words of each layout dictionary "
                        "(--method paper: k-means centres of each view)"),
    "eta": ("eta", "PSLF shared proportion of latent factors Kc/K, in (0, 1]; --method paper only"),
    "lam": ("lam", "PSLF smoothness of the view weights (lambda); --method paper only"),
    "beta": ("beta", "PSLF weight of the label term (eq. 2); --method paper only"),
    "gamma": ("gamma", "PSLF l2,1 penalty on W (eq. 2); --method paper only"),
    "mu": ("mu", "patch reselection threshold (eq. 4), in [0, 1]"),
    "rounds": ("max_rounds", "cluster-and-reselect rounds at most"),
}
# PSLF's parameters: only the paper's method runs PSLF (the default fuses its views' graphs), so
# with the default method a value given for one of these would change nothing, and is refused
PAPER_ONLY = ("eta", "lam", "beta", "gamma")
METHOD_HELP = ("'default' (this extension's method, see README) or 'paper' (sections 3-4.5 "
               "as written)")

# What `analyze` writes into --out; a folder holding anything else is not ours to replace.
RESULT_ENTRIES = ("result.blend", "result.blend1", "report.json", "report.html", "images",
                  "style_space.npz", "identify.csv", "identify.json")


def default(option: str):
    """The default value of a PARAMETERS option (from AnalysisParams)."""
    return getattr(DEFAULTS, PARAMETERS[option][0])


def help_text(option: str) -> str:
    return f"{PARAMETERS[option][1]} (default {default(option)})"


@dataclass
class JobOptions:
    renderer: str = "freestyle"
    up: str = "z"
    suggestive_contours: bool = False
    jobs: int = 0                       # 0: all cores
    cache_dir: str | None = None
    seed: int = 0
    params: AnalysisParams = field(default_factory=AnalysisParams)
    localisation: LocalisationParams = field(default_factory=LocalisationParams)
    labels: dict | None = None          # name -> style
    triplets: list | None = None        # (a, b, c): a closer in style to b than to c
    n_seeds: int = 30                   # seeds per shape for the analysis (paper 4.1)
    cancel: object = None               # optional callable -> bool, polled at every step

    def drawing_settings(self) -> DrawingSettings:
        # seed_multiplier times n_seeds seeds are drawn; seeds come in farthest-point order, so
        # the first n_seeds of them are themselves an evenly spread set for the analysis
        return DrawingSettings(renderer=self.renderer, up=self.up,
                               suggestive_contours=self.suggestive_contours,
                               n_seeds=self.n_seeds * self.localisation.seed_multiplier,
                               seed=self.seed)


def parse_clusters(value) -> int | None:
    """'auto' (or None) -> None; a whole number >= 2 -> itself; anything else is refused."""
    if value is None or str(value).strip().lower() == "auto":
        return None
    try:
        k = int(str(value).strip())
    except ValueError:
        k = 0
    if k < 2:
        raise InputError(f"--clusters must be 'auto' or a whole number of at least 2, not '{value}'")
    return k


def _number(problems, name, value, *, low=None, high=None, low_open=False, whole=False):
    if whole:
        ok = isinstance(value, int) and not isinstance(value, bool)
    else:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if ok and low is not None:
        ok = value > low if low_open else value >= low
    if ok and high is not None:
        ok = value <= high
    if not ok:
        rng = ("(" if low_open else "[") + f"{low if low is not None else '-inf'}, " \
            f"{high if high is not None else 'inf'}" + ("]" if high is not None else ")")
        kind = "a whole number" if whole else "a number"
        problems.append(f"--{name} must be {kind} in {rng}, not {value!r}")


def suggestive_problem(renderer: str) -> str:
    """Why --suggestive-contours cannot go with `renderer` (any but freestyle): said before any
    work, not found out shape by shape (zbuffer) or silently not drawn (lineart)."""
    return (f"--suggestive-contours: only the freestyle renderer draws them (--renderer {renderer} "
            "draws silhouettes, borders and creases); use --renderer freestyle or leave it out")


def build_options(*, renderer: str = "freestyle", up: str = "z", suggestive_contours=False,
                  jobs: int = 0, cache_dir=None, seed: int = 0, clusters="auto",
                  method: str | None = None, labels=None, triplets=None, **params) -> JobOptions:
    """JobOptions from raw values; `params` are PARAMETERS options (None: the default).

    `labels` / `triplets`: a dict / list, or the path of a CSV read later by `load_constraints`.

    Raises InputError listing every problem found (all at once, so a person fixes them in one go).
    """
    problems = []
    unknown = sorted(set(params) - set(PARAMETERS))
    if unknown:
        raise TypeError(f"unknown parameter(s): {', '.join(unknown)}")
    values = {opt: (default(opt) if params.get(opt) is None else params[opt]) for opt in PARAMETERS}
    if isinstance(values["representatives"], float) and values["representatives"].is_integer():
        values["representatives"] = int(values["representatives"])
    if isinstance(values["rounds"], float) and values["rounds"].is_integer():
        values["rounds"] = int(values["rounds"])
    method = DEFAULTS.method if method is None else str(method).lower()
    if renderer not in RENDERERS:
        problems.append(f"--renderer must be one of {', '.join(RENDERERS)}, not {renderer!r}")
    elif suggestive_contours and renderer != "freestyle":
        problems.append(suggestive_problem(renderer))
    if up not in UP_AXES:
        problems.append(f"--up must be one of {', '.join(UP_AXES)}, not {up!r}")
    if method not in METHODS:
        problems.append(f"--method must be one of {', '.join(METHODS)}, not {method!r}")
    unread = [f"--{o} {params[o]!r}" for o in PAPER_ONLY if params.get(o) is not None]
    if method == "default" and unread:
        problems.append(f"{', '.join(unread)}: only the paper's method reads "
                        f"{'this PSLF parameter' if len(unread) == 1 else 'these PSLF parameters'}"
                        " (the default method fuses its views without PSLF); add --method paper, "
                        f"or leave {'it' if len(unread) == 1 else 'them'} out")
    _number(problems, "jobs", jobs, low=0, whole=True)
    _number(problems, "seed", seed, low=0, high=2 ** 32 - 1, whole=True)
    _number(problems, "representatives", values["representatives"], low=2, whole=True)
    _number(problems, "eta", values["eta"], low=0, high=1, low_open=True)
    for opt in ("lam", "beta", "gamma"):
        _number(problems, opt, values[opt], low=0)
    _number(problems, "mu", values["mu"], low=0, high=1)
    _number(problems, "rounds", values["rounds"], low=1, whole=True)
    try:
        n_clusters = parse_clusters(clusters)
    except InputError as exc:
        problems.append(str(exc))
        n_clusters = None
    if labels and triplets:
        problems.append("give style labels or triplets, not both (labels: "
                        f"{len(labels)} shapes, triplets: {len(triplets)})")
    if problems:
        raise InputError("; ".join(problems))
    analysis = AnalysisParams(**{**{f.name: getattr(DEFAULTS, f.name) for f in fields(DEFAULTS)},
                                 **{PARAMETERS[o][0]: v for o, v in values.items()},
                                 "method": method, "n_clusters": n_clusters,
                                 "random_state": seed})
    if labels and not isinstance(labels, (str, os.PathLike)):
        labels = dict(labels)
    if triplets and not isinstance(triplets, (str, os.PathLike)):
        triplets = [tuple(t) for t in triplets]
    return JobOptions(renderer=renderer, up=up, suggestive_contours=bool(suggestive_contours),
                      jobs=jobs, cache_dir=cache_dir, seed=seed, params=analysis,
                      labels=labels or None, triplets=triplets or None)


def load_constraints(options: JobOptions, names) -> None:
    """Read constraint files given as paths (the command's --labels / --triplets) now that the
    shapes' names are known; dicts and lists (the operator's) are kept as they are."""
    if isinstance(options.labels, (str, os.PathLike)):
        options.labels = read_labels(options.labels, names)
    if isinstance(options.triplets, (str, os.PathLike)):
        options.triplets = read_triplets(options.triplets, names)


def check_shapes(options: JobOptions, names: list[str], skipped: dict | None = None) -> None:
    """What needs the analysable shapes: at least two, clusters <= shapes, constraint names known
    and the constraints themselves sound (two styles or more, no contradictory triplets), and
    with labels, clusters = labelled styles.

    `skipped` (name -> reason) explains names that were dropped."""
    skipped = skipped or {}
    known = set(names)
    mentioned = set(options.labels or ()) | {n for t in (options.triplets or ()) for n in t}
    missing = sorted(mentioned - known)
    if missing:
        why = [f"'{n}' ({skipped[n]})" if n in skipped else f"'{n}'" for n in missing]
        raise InputError("constraints name shapes that are not in the analysed set: " + ", ".join(why))
    if len(names) < 2:
        raise InputError("need at least two analysable meshes, found %d%s" % (
            len(names), (" (skipped: " + "; ".join(f"'{k}' {v}" for k, v in skipped.items()) + ")")
            if skipped else ""))
    k = options.params.n_clusters
    if k is not None and k > len(names):
        raise InputError(f"--clusters {k} asks for more clusters than the {len(names)} "
                         "analysable shapes")
    from .constraints import validate_labels, validate_triplets
    if options.labels:                   # the panel's come as a dict, not through a CSV reader
        validate_labels(options.labels)
    if options.triplets:
        validate_triplets(options.triplets)
    styles = sorted(set((options.labels or {}).values()))
    if k is not None and styles and k != len(styles):
        # both methods make one cluster per labelled style: any other count would be ignored
        raise InputError(f"--clusters {k} with labels of {len(styles)} styles "
                         f"({', '.join(styles)}): with labels there is one cluster per labelled "
                         f"style; leave --clusters out (or auto), or label shapes of {k} styles")


COORDINATE_LIMIT = 1e30    # beyond this a coordinate is corrupt, whatever the unit


def check_coordinates(mesh) -> None:
    """Refuse a shape with NaN, infinite or absurd (beyond 1e30) coordinates, naming it. Such a
    vertex is damage, not geometry: the run stops rather than analyse a shape of garbage."""
    import numpy as np
    v = np.asarray(mesh.vertices, np.float64)
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(v) <= COORDINATE_LIMIT).all(axis=1) if v.size else np.zeros(0, bool)
    if bad.any():
        nan = int((~np.isfinite(v)).any(axis=1).sum())
        raise InputError(f"'{mesh.name}' has {int(bad.sum())} vertices with NaN, infinite or "
                         f"absurd (beyond {COORDINATE_LIMIT:g}) coordinates ({nan} not finite); "
                         f"the first is vertex {int(np.argmax(bad))}")


# ------------------------------------------------------------------ constraint files
def _first_row(path) -> tuple[int, list[str]] | None:
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError):
        return None                      # constraints' own reader reports it
    for lineno, line in enumerate(text.splitlines(), start=1):
        if line.strip() and not line.lstrip().startswith("#"):
            return lineno, [c.strip() for c in next(csv.reader([line]))]
    return None


def _read_with_header_hint(reader, path, names, header: tuple):
    """Run a constraints reader; when its first row is not the expected header and names no
    analysed shape, say which header was expected rather than only 'unknown name'."""
    try:
        return reader(path, names)
    except InputError as exc:
        first = _first_row(path)
        if first is None or "not among the analysed shapes" not in str(exc):
            raise
        lineno, cells = first
        if tuple(c.lower() for c in cells) == header or set(cells) & set(names):
            raise
        raise InputError(f"{path}, line {lineno}: '{','.join(cells)}' is not a header this file "
                         f"may have: the header must be '{','.join(header)}' (or left out). "
                         f"{exc}") from None


def read_labels(path, names) -> dict[str, str]:
    from . import constraints
    return _read_with_header_hint(constraints.read_labels_csv, path, names,
                                  constraints.LABEL_HEADER)


def read_triplets(path, names) -> list[tuple[str, str, str]]:
    from . import constraints
    return _read_with_header_hint(constraints.read_triplets_csv, path, names,
                                  constraints.TRIPLET_HEADER)


# ------------------------------------------------------------------ the output folder
def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def check_output(out, inputs=(), cache_dir=None) -> Path:
    """Refuse an --out the command could not write completely or that would lose data.

    `analyze` replaces --out as a whole (see `publish`), so --out must not hold an input (INPUT,
    its folder, the CSVs), the cache, or files that are not a previous result; it must not lie
    inside a folder INPUT either (the input is never written), and its parent must be writable.
    Inputs that do not exist are reported first. Returns the resolved path.
    """
    for p in inputs:
        if p is not None and not os.path.exists(p):
            raise InputError(f"'{p}' does not exist")
    out = Path(os.path.abspath(os.fspath(out))).resolve()
    if out.exists() and not out.is_dir():
        raise InputError(f"--out '{out}' is an existing file, not a folder")
    for p in inputs:
        if p is None:
            continue
        p = Path(os.path.abspath(os.fspath(p))).resolve()
        if _inside(p, out):
            raise InputError(f"--out '{out}' would overwrite the input '{p}': the result "
                             "replaces --out as a whole, choose a folder that holds no input")
        if p.is_dir() and _inside(out, p):
            raise InputError(f"--out '{out}' is inside the input folder '{p}': the input is "
                             "never written, choose a folder outside it")
    if cache_dir:
        c = Path(os.path.abspath(os.fspath(cache_dir))).resolve()
        if _inside(c, out):
            raise InputError(f"--cache '{c}' is inside --out '{out}', which is replaced as a "
                             "whole: put the cache elsewhere")
    if out.is_dir():
        foreign = sorted(p.name for p in out.iterdir() if p.name not in RESULT_ENTRIES)
        if foreign:
            shown = ", ".join(foreign[:5]) + (", ..." if len(foreign) > 5 else "")
            raise InputError(f"--out '{out}' holds files that are not a previous result ({shown}): "
                             "it would be replaced as a whole, choose a new or empty folder")
    # the parent must take a temporary folder (written first, then moved into place)
    existing = out.parent
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise InputError(f"--out '{out}': '{existing}' is a file, not a folder")
    try:   # a real write (os.access says yes to root even on read-only file systems)
        probe = tempfile.mkdtemp(prefix=f".{out.name}.probe-", dir=existing)
        os.rmdir(probe)
    except OSError as exc:
        raise InputError(f"--out '{out}': cannot write in '{existing}' ({exc.strerror})") from None
    return out


def _exchange(a: Path, b: Path) -> bool:
    """Swap two existing paths in one step (Linux renameat2 RENAME_EXCHANGE); False if unsupported."""
    if not hasattr(os, "uname") or os.uname().sysname != "Linux":
        return False
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    AT_FDCWD, RENAME_EXCHANGE = -100, 2
    rc = fn(AT_FDCWD, os.fsencode(a), AT_FDCWD, os.fsencode(b), RENAME_EXCHANGE)
    return rc == 0


def publish(out, write) -> Path:
    """Write a complete result into --out, or leave --out as it was.

    `write(folder)` fills a temporary folder beside `out` (same file system); the finished folder
    then replaces `out` in one rename (an exchange on Linux), so `out` always holds a complete
    previous result or the complete new one. An interruption or error removes the temporary folder.
    """
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o777 & ~umask)       # mkdtemp makes it private; a result folder is not
    old = tmp.with_name(tmp.name.replace(".tmp-", ".old-"))
    moved_old = done = False
    try:
        write(tmp)
        if out.exists() and _exchange(tmp, out):
            done = True                  # tmp now holds the previous result
        else:
            if out.exists():
                os.rename(out, old)
                moved_old = True
            os.rename(tmp, out)
            done = True
    finally:
        if not done and moved_old and not out.exists():
            os.rename(old, out)          # interrupted between the two renames: put it back
        import shutil
        shutil.rmtree(tmp, ignore_errors=True)
        if done:
            shutil.rmtree(old, ignore_errors=True)
    return out
