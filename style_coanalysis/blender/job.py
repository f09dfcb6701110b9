"""The whole analysis of a set of meshes as one generator of progress steps.

Why a generator: the headless command simply runs it to the end, while the panel's modal
operator steps it from TIMER events so the interface stays responsive and Esc can stop it
between steps (`bpy.app.timers` do not fire in background mode, see BLENDER_NOTES). Nothing here
touches the user's scene: the result is plain data, written back by `writeback` only once the
whole run has succeeded, so a cancelled or failed run changes nothing.

Where rendering happens is decided before it starts (`batch.draw_steps`): in worker processes
(jobs > 1 with Blender as a module), or else in this thread, one view per step. bpy never runs on
another thread. The HOG maps and style regions, pure per-shape work, run in as many plain
processes (`parallel`); the global analysis, pure numpy that never touches bpy, runs in a
worker thread while the generator keeps yielding its progress.

Steps are (stage, done, total) or (stage, done, total, detail), detail a short text about the
work inside the current unit (which shape, which view).
"""
from __future__ import annotations

import threading
import time
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from .. import localisation, metrics
from ..meshes import InputError, Mesh, normalisation, normalise, to_world, validate
from ..options import JobOptions, check_coordinates, check_shapes  # noqa: F401 (re-exported)
from ..progress import Cancelled
from ..rig import Rig
from . import batch

STAGES = ("render", "analyse", "localise")


@dataclass
class ShapeOutcome:
    name: str
    cluster: int
    label: str | None
    label_given: bool
    confidence: float
    best_view: int
    best_view_matrix: list              # 4x4 camera-to-world matrix (Blender camera convention)
    vertex_weights: np.ndarray          # (N,) float32 in [0, 1], the object's vertex order
    style_vertex_fraction: float


@dataclass
class JobResult:
    shapes: list
    clusters: list                      # dicts: id, size, members, label
    skipped: list                       # (name, reason)
    report: dict
    analysis: object = None             # pipeline.AnalysisResult
    drawings: list = field(default_factory=list)
    localisations: list = field(default_factory=list)
    style_space: object = None          # similarity.StyleSpace: what the later uses read


def camera_matrix(rig: Rig, view: int, centre, radius: float, up: str) -> list:
    """Camera-to-world 4x4 of a rig view in the user's frame (Blender: looks down -Z, +Y up)."""
    right, upv, fwd = rig.frames()[view]
    cols = [to_world(d, 0.0, 1.0, up) for d in (right, upv, -fwd)]
    loc = to_world(rig.locations()[view], centre, radius, up)
    m = np.eye(4)
    for k, c in enumerate(cols):
        m[:3, k] = c
    m[:3, 3] = loc
    return m.tolist()


def _in_thread(fn, progress_box: list, cancel_flag: threading.Event):
    """Run fn() in a thread; yield its latest progress until it ends; return its value."""
    out: dict = {}

    def work():
        try:
            out["value"] = fn()
        except BaseException as exc:  # re-raised in the generator's thread
            out["error"] = exc

    t = threading.Thread(target=work, daemon=True)
    t.start()
    try:
        while t.is_alive():
            t.join(0.1)
            yield progress_box[0]
    except GeneratorExit:       # a cancel: let the thread see the flag and stop
        cancel_flag.set()
        t.join()
        raise
    except BaseException:       # Ctrl-C: the thread is a daemon, do not wait for it
        cancel_flag.set()
        raise
    if "error" in out:
        raise out["error"]
    return out["value"]


def run_steps(meshes: list[Mesh], options: JobOptions):
    """Generator: yields (stage, done, total); returns a JobResult. Raises InputError, Cancelled."""
    steps = _run_steps(meshes, options)
    try:
        for step in steps:
            if isinstance(step, JobResult):
                return step
            if options.cancel is not None and options.cancel():
                raise Cancelled(f"cancelled during '{step[0]}'")
            yield step
    finally:
        steps.close()   # a closed or cancelled run stops its worker thread and processes now


def _run_steps(meshes: list[Mesh], options: JobOptions):
    """run_steps' body: yields progress steps, then the JobResult itself as its last item."""
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    skipped: dict[str, str] = {}
    good: list[Mesh] = []
    for m in meshes:
        check_coordinates(m)  # corrupt coordinates: refuse the run, naming the shape
        try:
            validate(m)
            good.append(m)
        except InputError as exc:  # no faces, degenerate: skipped, listed in the report
            skipped[m.name] = str(exc).replace(f"'{m.name}' ", "")
    # every check that needs the shapes or this Blender, before the first render
    check_shapes(options, [m.name for m in good], skipped)
    from .render import check_renderer
    check_renderer(options.renderer)

    # 1. drawings (per shape, cached): in worker processes or, one view per step, right here
    settings = options.drawing_settings()
    t0 = time.perf_counter()
    cancel_flag = threading.Event()
    user_cancel = options.cancel or (lambda: False)

    def stop() -> bool:
        return cancel_flag.is_set() or bool(user_cancel())
    box = [("render", 0, len(good))]

    def progress(stage, done, total):
        box[0] = (stage, done, total)

    drawings, bad = yield from batch.draw_steps(good, settings, options.cache_dir,
                                                jobs=options.jobs)
    skipped.update(dict(bad))
    timings["render"] = time.perf_counter() - t0
    by_name = {d.name: d for d in drawings}
    good = [m for m in good if m.name in by_name]
    drawings = [by_name[m.name] for m in good]
    check_shapes(options, [m.name for m in good], skipped)   # some shapes may not draw

    # 2. the analysis, on the first n_seeds seeds of each shape; the HOG maps are computed
    # once here because the style regions (stage 3) read them too, and cached beside the
    # drawings so a second run reads them. The maps and regions not cached are computed in
    # `jobs` plain processes (`parallel`), in order: the serial result. The analysis runs in
    # one: its encoding's matrix products already use every core through their threads.
    from .. import pipeline
    from ..cache import (AnalysisCache, HogCache, RegionCache, analysis_key, cache_key,
                         drawings_digest, hog_key, images_digest, region_key)
    from ..features import MapStore, hog_images
    from ..parallel import in_processes
    t0 = time.perf_counter()
    cached = options.cache_dir is not False
    hogs = HogCache(options.cache_dir) if cached else None
    maps = MapStore()       # on disk: a collection's maps need not fit in memory
    # each shape's images digest: the HOG key, part of the analysis key
    sums = [images_digest(d.images) for d in drawings] if cached else []
    # which maps are cached is decided up front, for the workers; each is read only when the
    # store takes it, so a cached collection's maps are never all in memory
    present = [hogs.path(hog_key(s)).exists() for s in sums] if hogs is not None else \
        [False] * len(drawings)
    missing = [i for i, p in enumerate(present) if not p]
    workers = batch.effective_jobs(options.jobs, len(drawings))
    computed = in_processes(hog_images, ({"images": drawings[i].images} for i in missing),
                            len(missing), workers)
    try:
        for i, d in enumerate(drawings):
            yield ("hog", i, len(drawings))
            m = hogs.load(hog_key(sums[i])) if present[i] else None
            if m is None:       # not cached, or an entry found damaged now: computed here
                m = next(computed) if not present[i] else hog_images(d.images)
                if hogs is not None:
                    hogs.store(hog_key(sums[i]), m)
            maps.append(m)
    finally:
        computed.close()    # a cancel ends the workers now
    timings["hog"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    analysis_drawings = [seed_subset(d, options.n_seeds) for d in drawings]
    # the same shapes, parameters and constraints as a cached run: its result, not a re-run
    analyses = AnalysisCache(options.cache_dir) if cached else None
    key = result = None
    if analyses is not None:
        key = analysis_key([drawings_digest(d, s) for d, s in zip(analysis_drawings, sums)],
                           options.params.as_dict(), options.labels, options.triplets)
        result = analyses.load(key, [d.name for d in analysis_drawings])
    if result is not None:
        yield ("analyse", 1, 1, "from the cache")
    else:
        box[0] = ("analyse", 0, 1)
        result = yield from _in_thread(
            lambda: pipeline.analyse(analysis_drawings, options.params, labels=options.labels,
                                     triplets=options.triplets, progress=progress,
                                     cancel=stop, maps=maps, cache_dir=options.cache_dir),
            box, cancel_flag)
        for k, v in (result.timings or {}).items():
            timings[f"analyse.{k}"] = v
        if analyses is not None:
            analyses.store(key, result)
    timings["analyse"] = time.perf_counter() - t0

    # 3. style regions and best views, per shape
    t0 = time.perf_counter()
    rig = Rig(n_views=settings.n_views, elevation_deg=settings.elevation_deg,
              image_size=settings.image_size)
    locs, shapes = [], []
    marked_words = localisation.top_words(result.word_cluster, result.word_score,
                                          options.localisation.words_per_cluster)
    # each shape's regions are cached under the analysis they come from (same key, same result)
    regions = RegionCache(options.cache_dir) if key is not None else None
    where = {**asdict(options.localisation), "patch_size": options.params.patch_size}
    rkeys = [region_key(key, cache_key(m, settings), i, where) if regions is not None else None
             for i, m in enumerate(good)]
    found = {}
    for i, rkey in enumerate(rkeys):
        hit = regions.load(rkey) if rkey is not None else None
        if hit is not None:
            found[i] = hit
    missing = [i for i in range(len(good)) if i not in found]

    def task(i: int) -> dict:
        normal = normalise(good[i], options.up)
        return {"drawings": drawings[i], "vertices": normal.vertices, "faces": normal.faces,
                "cluster": int(result.clusters[i]), "maps": maps[i]}
    computed = in_processes(
        localisation.localise_shape, (task(i) for i in missing), len(missing), workers,
        shared={"words": result.words, "word_cluster": marked_words,
                "patch_size": options.params.patch_size,
                "threshold": options.localisation.match_threshold})
    try:
        for i, m in enumerate(good):
            yield ("localise", i, len(good))
            loc = found.pop(i, None)
            if loc is None:
                loc = next(computed)
                if rkeys[i] is not None:
                    regions.store(rkeys[i], loc)
            locs.append(loc)
            centre, radius = normalisation(m, options.up)
            given = bool(result.label_given[i])
            label = result.predicted[i] if result.predicted is not None else None
            shapes.append(ShapeOutcome(
                name=m.name, cluster=int(result.clusters[i]), label=label, label_given=given,
                confidence=float(result.confidence[i]), best_view=loc.best_view,
                best_view_matrix=camera_matrix(rig, loc.best_view, centre, radius, options.up),
                vertex_weights=loc.weights,
                style_vertex_fraction=float((loc.weights > 0.5).mean())))
    finally:
        computed.close()
    maps.close()
    timings["localise"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start

    clusters = []
    for c in range(result.n_clusters):
        members = [s.name for s in shapes if s.cluster == c]
        label = None
        if result.predicted is not None and members:
            names, counts = np.unique([s.label for s in shapes if s.cluster == c], return_counts=True)
            label = str(names[np.argmax(counts)])
        clusters.append({"id": c, "size": len(members), "members": members, "label": label})
    report = build_report(good, shapes, clusters, skipped, options, timings, result, locs)
    from ..similarity import StyleSpace
    space = StyleSpace.from_result(result, triplets=options.triplets,
                                   random_state=options.params.random_state)
    yield ("done", len(good), len(good))
    yield JobResult(shapes, clusters, sorted(skipped.items()), report, result, drawings, locs,
                    space)


def seed_subset(d, n: int):
    """The same drawings with only the first n seeds (the analysis' share of them)."""
    return replace(d, seeds=d.seeds[:n], seed_faces=d.seed_faces[:n],
                   seed_visible=d.seed_visible[:, :n], seed_pixels=d.seed_pixels[:, :n])


def build_report(meshes, shapes, clusters, skipped, options, timings, result, locs) -> dict:
    """report.json's content; scores appear only when the input carries ground truth."""
    from dataclasses import asdict
    report = {
        "parameters": {
            "drawing": asdict(options.drawing_settings()) | {"n_seeds_analysis": options.n_seeds},
            "analysis": options.params.as_dict(),
            "localisation": asdict(options.localisation),
            "labels": len(options.labels or {}), "triplets": len(options.triplets or []),
            "jobs": options.jobs,
        },
        "seconds": {k: round(v, 3) for k, v in timings.items()},
        "shapes": [{"name": s.name, "source": m.source, "cluster": s.cluster, "label": s.label,
                    "label_given": s.label_given, "confidence": round(s.confidence, 4),
                    "style_vertex_fraction": round(s.style_vertex_fraction, 4),
                    "best_view": s.best_view} for s, m in zip(shapes, meshes)],
        "clusters": clusters,
        "skipped": [{"name": n, "reason": r} for n, r in sorted(skipped.items())],
        "rounds": list(result.rounds or []),
        "n_style_filters": len(result.style_filters),
    }
    if result.k_gaps:                     # the number of clusters was chosen from the data
        report["automatic_k"] = {"chosen": int(result.n_clusters),
                                 "gaps": {str(k): round(g, 4) for k, g in result.k_gaps.items()}}
    if result.dictionary_agreement is not None:     # unsupervised: how firm the clusters are
        report["dictionary_agreement"] = round(result.dictionary_agreement, 4)
    styles = [m.truth.get("style") for m in meshes]
    if all(s is not None for s in styles):
        pred = np.array([s.cluster for s in shapes])
        report["scores"] = {"style": metrics.score(pred, styles)}
        cats = [m.truth.get("category") for m in meshes]
        if all(c is not None for c in cats):
            report["scores"]["category"] = metrics.score(pred, cats)
    masks = [m.truth.get("face_mask") for m in meshes]
    if all(mask is not None for mask in masks):
        report["scores"]["localisation"] = localisation_scores(meshes, locs, masks)
    return report


def localisation_scores(meshes, locs, masks) -> dict:
    """Faces with style weight > 0.5 against the true decorative faces (metrics.region_scores),
    areas in each shape's normalised frame (as bench/bench_localisation.py): files come in any
    unit, and world areas would let the largest shapes decide the figure."""
    from ..meshes import face_areas
    preds = [loc.face_weights > 0.5 for loc in locs]
    areas = [face_areas(normalise(m).vertices, m.faces) for m in meshes]
    return metrics.region_scores(preds, masks, areas)
