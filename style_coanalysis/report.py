"""report.json and report.html: what a person reads after a run.

The page is read by looking: a summary in words at the top, a map of the shapes by style, a
confusion table against the given labels (and the ground truth when the input carries it), then
per cluster a strip of its most typical shapes, a gallery of its style patches (each word shown
by the window of the drawings most like it, with its shape and view) and every member's best
view with the matched style patches boxed beside a shaded view of its style regions, and last
the shapes the analysis is least sure of. Images are PNG files beside the page (images/): it
needs no server and no network. Everything is drawn with PIL, which the extension already
bundles (scikit-image needs it), so the same report comes out of the panel inside Blender, where
matplotlib is not there. The shaded view is a painter's-algorithm fill of the projected
triangles: enough for a 200-pixel thumbnail, and it needs no render engine.
"""
from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from . import atomic
from .graph import choose_n_clusters
from .rig import project

ORANGE = np.array([255, 140, 0], np.float64)
GREY = np.array([200, 200, 205], np.float64)
# Okabe-Ito and Tableau colours: distinguishable for most colour-blind readers
PALETTE = [(0, 114, 178), (230, 159, 0), (0, 158, 115), (204, 121, 167), (86, 180, 233),
           (213, 94, 0), (240, 228, 66), (127, 127, 127), (148, 103, 189), (140, 86, 75)]
TYPICAL = 6          # shapes in a cluster's strip
PATCHES = 12         # style patches in a cluster's gallery
LEAST_SURE = 8       # shapes in the "least sure" section
PATCH_ZOOM = 3       # style patches are small (24 px): shown three times larger


def write_json(report: dict, path) -> None:
    atomic.write_text(path, json.dumps(report, indent=2, default=_json_default))


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o).__name__)


def colour(cluster: int) -> tuple:
    return PALETTE[int(cluster) % len(PALETTE)]


def lines_image(ink: np.ndarray, boxes, size: int) -> Image.Image:
    """Ink black on white, with each (x, y) patch centre boxed in orange."""
    img = Image.fromarray((255 * (1.0 - np.clip(ink, 0, 1))).astype(np.uint8)).convert("RGB")
    draw = ImageDraw.Draw(img)
    h = size / 2
    for x, y in boxes:
        draw.rectangle([x - h, y - h, x + h, y + h], outline=(255, 140, 0), width=2)
    return img


def patch_image(ink: np.ndarray, x: float, y: float, size: int, zoom: int = PATCH_ZOOM) -> Image.Image:
    """The size x size patch of a drawing centred on (x, y) (paper left blank outside the
    image), black on white, enlarged `zoom` times without smoothing."""
    h, w = ink.shape
    out = np.zeros((size, size), np.float32)
    r0, c0 = int(round(y - size / 2)), int(round(x - size / 2))
    rs, cs = slice(max(r0, 0), min(r0 + size, h)), slice(max(c0, 0), min(c0 + size, w))
    if rs.start < rs.stop and cs.start < cs.stop:
        out[rs.start - r0:rs.stop - r0, cs.start - c0:cs.stop - c0] = ink[rs, cs]
    img = Image.fromarray((255 * (1.0 - np.clip(out, 0, 1))).astype(np.uint8))
    return img.resize((size * zoom, size * zoom), Image.NEAREST)


def shaded_image(vertices: np.ndarray, faces: np.ndarray, weights: np.ndarray,
                 camera: np.ndarray, eye: np.ndarray, size: int, per_face: bool = False) -> Image.Image:
    """Flat-shaded mesh from one rig camera, style weight blended from grey to orange;
    `weights` per vertex, or per face with per_face=True."""
    pix, depth = project(camera[None], vertices)
    pix, depth = pix[0], depth[0]
    tri = vertices[faces].astype(np.float64)
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    to_eye = eye - tri.mean(axis=1)
    to_eye /= np.linalg.norm(to_eye, axis=1, keepdims=True)
    light = 0.35 + 0.65 * np.abs((normal * to_eye).sum(axis=1))   # two-sided headlight
    weights = np.asarray(weights, np.float64)
    w = weights if per_face else weights[faces].mean(axis=1)
    w = np.clip(w, 0, 1)[:, None]
    colours = ((1 - w) * GREY + w * ORANGE) * light[:, None]
    order = np.argsort(-depth[faces].mean(axis=1), kind="stable")   # far to near
    img = Image.new("RGB", (size, size), (255, 255, 255))
    draw = ImageDraw.Draw(img)
    for f in order:
        draw.polygon([tuple(p) for p in pix[faces[f]]], fill=tuple(int(c) for c in colours[f]))
    return img


def map_coordinates(coords: np.ndarray, random_state: int = 0) -> np.ndarray:
    """(N, 2) positions for the style map: t-SNE of the style coordinates (neighbours in style
    stay neighbours; the first two principal directions put overlapping clusters on top of each
    other), or those principal directions for very small collections where t-SNE cannot run."""
    coords = np.asarray(coords, np.float64)
    n = len(coords)
    if coords.ndim != 2 or coords.shape[1] < 2 or n < 3:
        return np.zeros((n, 2))
    if n < 10:
        from sklearn.decomposition import PCA
        return PCA(n_components=2, svd_solver="full").fit_transform(coords)
    from sklearn.manifold import TSNE
    return TSNE(n_components=2, perplexity=min(30.0, (n - 1) / 3), init="pca",
                random_state=random_state).fit_transform(coords)


def style_map(xy: np.ndarray, clusters, given, size: int = 440) -> Image.Image:
    """A dot per shape at its map position, coloured by cluster, with a black ring around each
    shape whose label was given."""
    xy = np.asarray(xy, np.float64)
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    margin = 16
    pix = margin + (xy - lo) / np.where(hi > lo, hi - lo, 1.0) * (size - 2 * margin)
    pix[:, 1] = size - pix[:, 1]                     # y up
    img = Image.new("RGB", (size, size), (255, 255, 255))
    draw = ImageDraw.Draw(img)
    draw.rectangle([0, 0, size - 1, size - 1], outline=(190, 190, 190))
    for (x, y), c, g in sorted(zip(pix, clusters, given), key=lambda t: t[2]):  # rings on top
        r = 5
        draw.ellipse([x - r, y - r, x + r, y + r], fill=colour(c))
        if g:
            draw.ellipse([x - r - 3, y - r - 3, x + r + 3, y + r + 3], outline=(0, 0, 0), width=2)
    return img


def typical_order(coords: np.ndarray, members: np.ndarray) -> np.ndarray:
    """The members (indices) ordered from the most typical: nearest their cluster's mean style
    coordinates. Not by confidence: every shape whose label was given has confidence 1."""
    coords = np.asarray(coords, np.float64)[members]
    d = np.linalg.norm(coords - coords.mean(axis=0), axis=1)
    return np.asarray(members)[np.argsort(d, kind="stable")]


def confusion(clusters, reference) -> tuple[list, np.ndarray]:
    """(reference classes, counts (n_clusters, n_classes)) over the shapes that have a reference
    (None where a shape has none)."""
    clusters = np.asarray(clusters)
    keep = [i for i, r in enumerate(reference) if r is not None]
    classes = sorted({str(reference[i]) for i in keep})
    n_c = int(clusters.max()) + 1 if len(clusters) else 0
    table = np.zeros((n_c, len(classes)), np.int64)
    for i in keep:
        table[clusters[i], classes.index(str(reference[i]))] += 1
    return classes, table


def cluster_count_note(report: dict) -> str:
    """How sure the automatic number of clusters is, in words ("" when the user gave it): the
    runner-up and its spectral gap against the chosen one's, so a person who sees styles merged
    or split knows which number to try (the automatic k is right on fewer than half of the
    generalisation benchmark's runs)."""
    auto = report.get("automatic_k")
    if not auto or len(auto["gaps"]) < 2:
        return ""
    chosen = int(auto["chosen"])
    gaps = {int(k): float(g) for k, g in auto["gaps"].items()}
    runner = choose_n_clusters({k: g for k, g in gaps.items() if k != chosen})
    share = gaps[runner] / gaps[chosen] if gaps[chosen] > 0 else 1.0
    return (f"The number of clusters was chosen from the data: {chosen}; the next likeliest is "
            f"{runner} (spectral gap {share:.2f} of {chosen}'s): if styles look merged or split, "
            f"give the number of clusters.")


# the dictionaries' agreement (pipeline._dictionary_agreement) at or above which clusters are
# called firm: on the generalisation benchmark (36 collections, 3 seeds, k given) 24 of the 33
# runs at or above it were at least 0.9 pure in style, 10 of the 75 below (README, "The report")
FIRM = 0.8


def _firm(report: dict) -> bool | None:
    """Whether the report's clusters are firm (None where no firmness is reported)."""
    agree = report.get("dictionary_agreement")
    return None if agree is None else agree >= FIRM


def firmness_note(report: dict) -> str:
    """How firmly the drawings hold unsupervised clusters, in words ("" with labels or
    triplets, or one dictionary): where independent draws of the style words cut otherwise,
    another seed or a re-exported file can regroup shapes, and the user should know before
    marking regions or decimating by them."""
    firm = _firm(report)
    if firm is None:
        return ""
    agree = report["dictionary_agreement"]
    head = f"the analysis's dictionaries of style words, each cut alone, agree with them at ARI " \
           f"{agree:.2f}"
    if firm:
        return f"The clusters are firm: {head}."
    return (f"The clusters are not firmly held: {head} (firm: {FIRM:.1f} or more), so the "
            f"drawings support other groupings nearly as well and another seed or a re-exported "
            f"file may regroup shapes; style labels on a few shapes per style steer it.")


def firmness_label(report: dict) -> str:
    """The firmness in a few words for the panel's sidebar ("" where no firmness is reported)."""
    firm = _firm(report)
    if firm is None:
        return ""
    return f"{'firm' if firm else 'not firm'} ({report['dictionary_agreement']:.2f})"


def run_notes(report: dict) -> list[tuple[str, str]]:
    """What a finished run tells its user besides the counts, as (level, text): the automatic
    number of clusters' runner-up, and how firm the clusters are ("WARNING" when not
    firm). The panel's Analyse operator reports them, the command prints them."""
    notes = [("INFO", cluster_count_note(report))]
    notes.append(("WARNING" if _firm(report) is False else "INFO", firmness_note(report)))
    return [(level, text) for level, text in notes if text]


def summary_sentence(report: dict, n_skipped: int) -> str:
    """The run in words: what was analysed, what was found, how good it is against truth."""
    n, k = len(report["shapes"]), len(report["clusters"])
    p = report["parameters"]
    words = [f"{n} shapes, {k} style cluster{'s' if k != 1 else ''}"]
    if p.get("labels"):
        words.append(f"{p['labels']} labelled")
    elif p.get("triplets"):
        words.append(f"{p['triplets']} triplets")
    else:
        words.append("no labels (unsupervised)")
    text = ", ".join(words) + "."
    sizes = sorted((c["size"] for c in report["clusters"]), reverse=True)
    text += " Cluster sizes " + ", ".join(map(str, sizes)) + "."
    for _, note in run_notes(report):
        text += " " + note
    sc = report.get("scores", {})
    if "style" in sc:
        text += (f" Against the ground truth the clusters are {100 * sc['style']['purity']:.0f}% pure"
                 f" in style (chance {100 * sc['style']['majority_share']:.0f}%)")
        if "category" in sc:
            text += f" and {100 * sc['category']['purity']:.0f}% in category (lower is better: style, not shape kind)"
        text += "."
    if "localisation" in sc:
        a, r = sc["localisation"]["area"], sc["localisation"]["random_area"]
        text += (f" The orange style regions cover the true ornament with precision {a['precision']:.2f}"
                 f" and IoU {a['iou']:.2f} by area (as many random faces: {r['precision']:.2f} / {r['iou']:.2f}).")
    if n_skipped:
        text += f" {n_skipped} shape{'s were' if n_skipped != 1 else ' was'} skipped (listed at the end)."
    total = report.get("seconds", {}).get("total")
    if total is not None:
        text += f" The run took {total:.0f} s."
    return text


def write_html(job, meshes_normalised, out_dir, title="Style co-analysis", progress=None) -> Path:
    """report.html plus images/ in out_dir, from a JobResult and the shapes' normalised meshes.
    `progress(stage, done, total)` is called per shape written."""
    out_dir = Path(out_dir)
    img_dir = out_dir / "images"
    img_dir.mkdir(parents=True, exist_ok=True)
    stems = image_stems([s.name for s in job.shapes])
    patch = job.report["parameters"]["analysis"]["patch_size"]
    index = {s.name: i for i, s in enumerate(job.shapes)}
    n_total = len(job.shapes)

    # per-shape pictures first: the strips, the least-sure list and the members all reuse them
    for i, (s, d, loc, m) in enumerate(zip(job.shapes, job.drawings, job.localisations, meshes_normalised)):
        if progress is not None:
            progress("report", i, n_total)
        v = s.best_view
        boxes = [(x, y) for (view, x, y, _) in loc.matches if view == v]
        lines_image(d.images[v], boxes, patch).save(img_dir / f"{stems[s.name]}_lines.png")
        shade = getattr(loc, "face_weights", None)
        shaded_image(m.vertices, m.faces, s.vertex_weights if shade is None else shade,
                     d.cameras[v], _camera_centre(d.cameras[v]), d.images.shape[-1],
                     per_face=shade is not None).save(img_dir / f"{stems[s.name]}_shaded.png")

    def thumb(name, width=120, both=False):
        """A shape's figure; the full one (both pictures) is the page's one plain <figure> per shape."""
        st = stems[name]
        s = job.shapes[index[name]]
        # a shape's own figure (width 200) is the one place its two images are referenced with
        # src='...': tests/test_guarantees.py counts those to tell a complete result (two per
        # shape); the strips and the least-sure list repeat them with src="..."
        q = "'" if width == 200 else '"'
        imgs = f"<img src={q}images/{st}_lines.png{q} width={width} alt='{html.escape(name)} lines'>"
        if both:
            imgs += (f"<img src={q}images/{st}_shaded.png{q} width={width} "
                     f"alt='{html.escape(name)} regions'>")
        label = f"{s.label}{' (given)' if s.label_given else ''}" if s.label else ""
        tag = "<figure>" if width == 200 else f"<figure class='thumb' style='border-top:4px solid rgb{colour(s.cluster)}'>"
        return (f"{tag}{imgs}<figcaption>"
                f"{html.escape(name)}<br>{html.escape(label)} sure {s.confidence:.2f}, view {s.best_view}"
                f"</figcaption></figure>")

    parts = [f"<!doctype html><html lang='en'><meta charset='utf-8'><title>{html.escape(title)}</title>",
             "<style>body{font-family:sans-serif;margin:2em;max-width:1300px}"
             "figure{display:inline-block;margin:4px;text-align:center;font-size:11px;vertical-align:top}"
             "img{border:1px solid #ccc}.lead{font-size:18px;line-height:1.5}"
             "table{border-collapse:collapse;margin:6px 0}td,th{padding:2px 8px;border-bottom:1px solid #eee}"
             ".sw{display:inline-block;width:12px;height:12px;margin:0 4px 0 12px;border-radius:6px}"
             "details{margin:8px 0}</style>",
             f"<h1>{html.escape(title)}</h1>",
             f"<p class='lead' id='summary'>{html.escape(summary_sentence(job.report, len(job.skipped)))}</p>"]

    analysis = job.analysis
    names = [s.name for s in job.shapes]
    clusters = np.array([s.cluster for s in job.shapes])
    given = [s.label_given for s in job.shapes]
    coords = getattr(analysis, "fused", None)
    if coords is not None and len(coords) != len(names):
        coords = None
    if coords is not None:
        style_map(map_coordinates(coords), clusters, given).save(img_dir / "style_map.png")
        legend = "".join(f"<span class='sw' style='background:rgb{colour(c['id'])}'></span>"
                         f"cluster {c['id']}{' (' + html.escape(c['label']) + ')' if c['label'] else ''}"
                         for c in job.clusters)
        parts.append("<h2>Shapes by style</h2><p>Each dot is a shape, placed by its style "
                     "(a t-SNE map of the style coordinates the clusters are cut from): near means "
                     "similar in style. Colour: cluster; black ring: label given."
                     f"</p><img id='style-map' src=\"images/style_map.png\" width=440 alt='style map'><p>{legend}</p>")
    parts.append(_confusion_html(job, meshes_normalised, clusters))

    parts.append("<h2>Clusters</h2>")
    filters = list(getattr(analysis, "style_filters", None) or [])
    for c in job.clusters:
        head = f"Cluster {c['id']}: {c['size']} shapes" + (f", style '{c['label']}'" if c["label"] else "")
        parts.append(f"<h3 style='border-left:8px solid rgb{colour(c['id'])};padding-left:6px'>"
                     f"{html.escape(head)}</h3>")
        members = [index[n] for n in c["members"]]
        if coords is not None and members:
            members = typical_order(coords, np.array(members))
        parts.append("<p>Most typical shapes (nearest the middle of the cluster in style):</p>"
                     + "".join(thumb(names[i]) for i in members[:TYPICAL]))
        gallery = _patch_gallery(c["id"], filters, job, img_dir, patch)
        if gallery:
            parts.append("<p>Its style patches: the line patterns that tell this cluster from the "
                         "others, each shown by the window of the drawings most like it:</p>"
                         + gallery)
        parts.append(f"<details open><summary>All {c['size']} members: best view with the style patches "
                     "boxed, and the style regions in orange</summary>"
                     + "".join(thumb(n, 200, both=True) for n in c["members"]) + "</details>")
    if progress is not None:
        progress("report", n_total, n_total)

    unsure = sorted(names, key=lambda n: job.shapes[index[n]].confidence)[:LEAST_SURE]
    if unsure:
        parts.append("<h2>Least sure</h2><p>The shapes whose cluster the analysis is least sure of "
                     "(lowest confidence): a label for one of them helps most.</p>"
                     + "".join(thumb(n, 160, both=True) for n in unsure))
    if job.skipped:
        parts.append("<h2>Skipped</h2><ul>" + "".join(
            f"<li>{html.escape(n)}: {html.escape(r)}</li>" for n, r in job.skipped) + "</ul>")
    parts.append("<h2>Figures</h2>" + _figures_html(job.report))
    page = out_dir / "report.html"
    page.write_text("\n".join(parts) + "\n</html>\n")
    return page


def _patch_gallery(cluster: int, filters, job, img_dir: Path, patch: int) -> str:
    """The cluster's best-scoring style patches, at most two from any one shape."""
    mine = sorted((f for f in filters if f.cluster == cluster), key=lambda f: -f.score)
    per_shape: dict = {}
    out = []
    for f in mine:
        if len(out) == PATCHES:
            break
        if per_shape.get(f.source_shape, 0) >= 2 or f.source_shape >= len(job.drawings):
            continue
        per_shape[f.source_shape] = per_shape.get(f.source_shape, 0) + 1
        name = job.shapes[f.source_shape].name
        file = f"patch_c{cluster}_{len(out)}.png"
        x, y = f.source_pixel
        patch_image(job.drawings[f.source_shape].images[f.view], x, y, patch).save(img_dir / file)
        out.append(f"<figure class='patch'><img src=\"images/{file}\" width={patch * PATCH_ZOOM} alt='style patch'>"
                   f"<figcaption>{html.escape(name)}<br>view {f.view}</figcaption></figure>")
    return "".join(out)


def _confusion_html(job, meshes, clusters) -> str:
    """Clusters against the given labels and, when the input carries it, the true styles."""
    out = []
    given = [s.label if s.label_given else None for s in job.shapes]
    truth = [m.truth.get("style") if getattr(m, "truth", None) else None for m in meshes]
    for title, ref in (("given labels", given), ("ground truth styles", truth)):
        if not any(r is not None for r in ref):
            continue
        classes, table = confusion(clusters, ref)
        head = "".join(f"<th>{html.escape(c)}</th>" for c in classes)
        rows = "".join(
            f"<tr><th align=left><span class='sw' style='background:rgb{colour(k)}'></span>cluster {k}</th>"
            + "".join(f"<td align=right{' style=font-weight:bold' if v and v == row.max() else ''}>{v}</td>"
                      for v in row) + "</tr>" for k, row in enumerate(table))
        out.append(f"<h3>Clusters against the {title}</h3><p>Shapes per cluster (rows) and "
                   f"{html.escape(title)} (columns); a clean result has one large number per row.</p>"
                   f"<table class='confusion'><tr><th></th>{head}</tr>{rows}</table>")
    return ("<h2>How the clusters match</h2>" + "".join(out)) if out else ""


def _figures_html(report: dict) -> str:
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
