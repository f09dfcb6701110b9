"""report.json and report.html: what a person reads after a run.

The HTML shows each cluster with its members' best-view line drawing (the matched style patches
boxed in orange) and a shaded view of the mesh from the same camera with its style regions in
orange. Images are separate PNG files beside the page (images/), so the page stays small.
The shaded view is a painter's-algorithm fill of the projected triangles (PIL): enough for a
200-pixel thumbnail, and it needs no render engine.
"""
from __future__ import annotations

import html
import json
import os
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from .rig import project

ORANGE = np.array([255, 140, 0], np.float64)
GREY = np.array([200, 200, 205], np.float64)


def write_json(report: dict, path) -> None:
    tmp = Path(str(path) + ".tmp")
    tmp.write_text(json.dumps(report, indent=2, default=_json_default))
    os.replace(tmp, path)


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o).__name__)


def lines_image(ink: np.ndarray, boxes, size: int) -> Image.Image:
    """Ink black on white, with each (x, y) patch centre boxed in orange."""
    img = Image.fromarray((255 * (1.0 - np.clip(ink, 0, 1))).astype(np.uint8)).convert("RGB")
    draw = ImageDraw.Draw(img)
    h = size / 2
    for x, y in boxes:
        draw.rectangle([x - h, y - h, x + h, y + h], outline=(255, 140, 0), width=2)
    return img


def shaded_image(vertices: np.ndarray, faces: np.ndarray, weights: np.ndarray,
                 camera: np.ndarray, eye: np.ndarray, size: int) -> Image.Image:
    """Flat-shaded mesh from one rig camera, style weight blended from grey to orange."""
    pix, depth = project(camera[None], vertices)
    pix, depth = pix[0], depth[0]
    tri = vertices[faces].astype(np.float64)
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    to_eye = eye - tri.mean(axis=1)
    to_eye /= np.linalg.norm(to_eye, axis=1, keepdims=True)
    light = 0.35 + 0.65 * np.abs((normal * to_eye).sum(axis=1))   # two-sided headlight
    w = np.clip(np.asarray(weights, np.float64)[faces].mean(axis=1), 0, 1)[:, None]
    colour = ((1 - w) * GREY + w * ORANGE) * light[:, None]
    order = np.argsort(-depth[faces].mean(axis=1))                  # far to near
    img = Image.new("RGB", (size, size), (255, 255, 255))
    draw = ImageDraw.Draw(img)
    for f in order:
        draw.polygon([tuple(p) for p in pix[faces[f]]], fill=tuple(int(c) for c in colour[f]))
    return img


def write_html(job, meshes_normalised, out_dir, title="Style co-analysis", progress=None) -> Path:
    """report.html plus images/ in out_dir, from a JobResult and the shapes' normalised meshes.
    `progress(stage, done, total)` is called per shape written."""
    out_dir = Path(out_dir)
    stems = image_stems([s.name for s in job.shapes])
    n_done, n_total = 0, len(job.shapes)
    img_dir = out_dir / "images"
    img_dir.mkdir(parents=True, exist_ok=True)
    patch = job.report["parameters"]["analysis"]["patch_size"]
    by_name = {s.name: (s, d, loc, m) for s, d, loc, m in
               zip(job.shapes, job.drawings, job.localisations, meshes_normalised)}
    parts = [f"<!doctype html><meta charset='utf-8'><title>{html.escape(title)}</title>",
             "<style>body{font-family:sans-serif;margin:2em}figure{display:inline-block;margin:4px;"
             "text-align:center;font-size:12px}img{border:1px solid #ccc}"
             "table{border-collapse:collapse}td,th{padding:2px 8px;border-bottom:1px solid #eee}</style>",
             f"<h1>{html.escape(title)}</h1>", _summary_html(job.report)]
    for c in job.clusters:
        head = f"Cluster {c['id']}: {c['size']} shapes" + (f", style '{c['label']}'" if c["label"] else "")
        parts.append(f"<h2>{html.escape(head)}</h2>")
        for name in c["members"]:
            if progress is not None:
                progress("report", n_done, n_total)
            n_done += 1
            s, d, loc, m = by_name[name]
            v = s.best_view
            boxes = [(x, y) for (view, x, y, _) in loc.matches if view == v]
            stem = stems[name]
            lines_image(d.images[v], boxes, patch).save(img_dir / f"{stem}_lines.png")
            eye = _camera_centre(d.cameras[v])
            shaded_image(m.vertices, m.faces, s.vertex_weights, d.cameras[v], eye,
                         d.images.shape[-1]).save(img_dir / f"{stem}_shaded.png")
            label = f"{s.label}{' (given)' if s.label_given else ''}" if s.label else ""
            parts.append(
                f"<figure><img src='images/{stem}_lines.png' width=200>"
                f"<img src='images/{stem}_shaded.png' width=200><figcaption>{html.escape(name)}"
                f"<br>{html.escape(label)} conf {s.confidence:.2f}, view {v}, "
                f"style {100 * s.style_vertex_fraction:.0f}%</figcaption></figure>")
    if job.skipped:
        parts.append("<h2>Skipped</h2><ul>" + "".join(
            f"<li>{html.escape(n)}: {html.escape(r)}</li>" for n, r in job.skipped) + "</ul>")
    page = out_dir / "report.html"
    page.write_text("\n".join(parts))
    if progress is not None:
        progress("report", n_total, n_total)
    return page


def _summary_html(report: dict) -> str:
    rows = [("shapes", len(report["shapes"])), ("clusters", len(report["clusters"])),
            ("style filters", report.get("n_style_filters", 0))]
    for key, scores in report.get("scores", {}).items():
        for sub, vals in _flat(scores, key):
            rows.append((f"scores: {sub}", ", ".join(
                f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}" for k, v in vals.items())))
    rows += [(f"seconds: {k}", v) for k, v in report["seconds"].items() if "." not in k]
    return "<table>" + "".join(f"<tr><th align=left>{html.escape(str(a))}</th><td>"
                               f"{html.escape(str(b))}</td></tr>" for a, b in rows) + "</table>"


def _flat(scores: dict, key: str):
    """(label, {metric: value}) rows: nested score groups (localisation) become one row each."""
    plain = {k: v for k, v in scores.items() if not isinstance(v, dict)}
    if plain:
        yield key, plain
    for k, v in scores.items():
        if isinstance(v, dict):
            yield f"{key} {k}", v


def _camera_centre(P: np.ndarray) -> np.ndarray:
    """Centre of a 3x4 projection matrix: its null vector."""
    _, _, vt = np.linalg.svd(P)
    c = vt[-1]
    return c[:3] / c[3]


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name)


def image_stems(names) -> dict:
    """A file-name stem per shape name, unique even where names differ only in characters a
    file name cannot hold ('a b' and 'a_b') or in case (file systems that ignore case): such
    names, and very long ones, get a short digest of the full name appended."""
    import hashlib
    safe = {n: _safe(n).lstrip(".") or "shape" for n in names}
    counts: dict = {}
    for n in names:
        counts[safe[n].lower()] = counts.get(safe[n].lower(), 0) + 1
    stems, taken = {}, set()
    for n in names:
        stem = safe[n]
        if counts[stem.lower()] > 1 or len(stem) > 100:
            stem = f"{stem[:100]}-{hashlib.sha1(n.encode('utf-8')).hexdigest()[:8]}"
        base, k = stem, 1
        while stem.lower() in taken:    # a digest equal to another shape's own name
            stem, k = f"{base}-{k}", k + 1
        taken.add(stem.lower())
        stems[n] = stem
    return stems
