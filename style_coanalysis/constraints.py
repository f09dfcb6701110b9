"""Style labels and triplets a person writes, read and checked before any analysis runs.

Files are small CSVs (`name,style` and `a,b,c` meaning "a is closer in style to b than to c").
A header row is optional, blank lines and `#` comments are ignored. Every problem is reported as
`meshes.InputError` naming the file and, for a bad row, its line; all unknown names are listed at
once so a person fixes the file in one go.
"""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from .meshes import InputError

LABEL_HEADER = ("name", "style")
TRIPLET_HEADER = ("a", "b", "c")


def _rows(path) -> list[tuple[int, list[str]]]:
    """(line number, stripped cells) of every non-blank, non-comment row."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read '{path}': {exc}") from None
    rows = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        cells = [c.strip() for c in next(csv.reader([line]))]
        while cells and cells[-1] == "":
            cells.pop()
        rows.append((lineno, cells))
    return rows


def _check_names(path, used: list[str], known_names) -> None:
    known = set(known_names)
    unknown = sorted({n for n in used if n not in known})
    if unknown:
        shown = ", ".join(f"'{n}'" for n in unknown)
        raise InputError(f"{path}: {len(unknown)} name(s) not among the analysed shapes: {shown}")


def read_labels_csv(path, known_names) -> dict[str, str]:
    """{shape name: style} from a `name,style` CSV; needs at least two different styles."""
    labels: dict[str, str] = {}
    where: dict[str, int] = {}
    rows = _rows(path)
    for i, (lineno, cells) in enumerate(rows):
        if i == 0 and tuple(c.lower() for c in cells) == LABEL_HEADER:
            continue
        if len(cells) != 2 or not all(cells):
            raise InputError(f"{path}, line {lineno}: expected 'name,style', got {','.join(cells)!r}")
        name, style = cells
        if name in labels and labels[name] != style:
            raise InputError(f"{path}, line {lineno}: '{name}' is labelled '{labels[name]}' on "
                             f"line {where[name]} and '{style}' here")
        labels[name], where[name] = style, lineno
    _check_names(path, list(labels), known_names)
    validate_labels(labels, source=str(path))
    return labels


def validate_labels(labels: dict[str, str], source: str = "labels") -> None:
    """Label mode needs two styles or more: one style gives nothing to separate."""
    styles = sorted(set(labels.values()))
    if len(styles) < 2:
        got = f"only '{styles[0]}'" if styles else "none"
        raise InputError(f"{source}: label mode needs at least two different styles, found {got}")


def read_triplets_csv(path, known_names) -> list[tuple[str, str, str]]:
    """[(a, b, c)] from an `a,b,c` CSV: a is closer in style to b than to c."""
    triplets = []
    for i, (lineno, cells) in enumerate(_rows(path)):
        if i == 0 and tuple(c.lower() for c in cells) == TRIPLET_HEADER:
            continue
        if len(cells) != 3 or not all(cells):
            raise InputError(f"{path}, line {lineno}: expected 'a,b,c', got {','.join(cells)!r}")
        if len(set(cells)) < 3:
            raise InputError(f"{path}, line {lineno}: a triplet must name three different shapes, "
                             f"got {','.join(cells)}")
        triplets.append(tuple(cells))
    _check_names(path, [n for t in triplets for n in t], known_names)
    validate_triplets(triplets, source=str(path))
    return triplets


def validate_triplets(triplets, source: str = "triplets") -> None:
    """Refuse a shape named twice in a triplet and pairs of triplets that contradict each other."""
    seen = {}
    for t in triplets:
        if len(t) != 3 or len(set(t)) < 3:
            raise InputError(f"{source}: a triplet must name three different shapes, got {t}")
        seen.setdefault(tuple(t), t)
    clashes = sorted({tuple(sorted([(a, b, c), (a, c, b)])) for (a, b, c) in seen
                      if (a, c, b) in seen})
    if clashes:
        shown = "; ".join(f"{x[0]} vs {x[1]}" for x in
                          ((",".join(p), ",".join(q)) for p, q in clashes))
        raise InputError(f"{source}: {len(clashes)} contradictory triplet pair(s) (a closer to b "
                         f"than c and closer to c than b): {shown}")
    if not triplets:
        raise InputError(f"{source}: no triplets found")


def labels_to_array(labels: dict[str, str], names: list[str]) -> tuple[np.ndarray, list[str]]:
    """(y (N,) int with -1 for unlabelled, classes sorted) for shapes in `names` order."""
    _check_names("labels", list(labels), names)
    classes = sorted(set(labels.values()))
    index = {c: k for k, c in enumerate(classes)}
    y = np.array([index[labels[n]] if n in labels else -1 for n in names], dtype=np.int64)
    return y, classes


def triplets_to_array(triplets, names: list[str]) -> np.ndarray:
    """(T, 3) int indices into `names` of each (a, b, c)."""
    _check_names("triplets", [n for t in triplets for n in t], names)
    index = {n: i for i, n in enumerate(names)}
    return np.array([[index[n] for n in t] for t in triplets], dtype=np.int64).reshape(-1, 3)
