"""Drawings for a whole collection: normalise, use the cache, render the rest in parallel.

Per-shape work is a pure function of (normalised mesh, settings) (DESIGN.md), so uncached shapes
go to worker processes and every result is cached by the parent (one writer per entry).

Parallelism:
- With Blender as a Python module (`bpy.app.binary_path == ""`, tests and the command line),
  `sys.executable` is the venv's Python, which can import bpy: workers are started with
  multiprocessing's 'spawn' method and each imports bpy and resets to factory settings itself.
- Inside Blender's GUI, `sys.executable` is Blender's bundled Python, which cannot import bpy,
  and a long render should stay cancellable from the UI: there we render in-process (jobs=1)
  whatever `jobs` asks for. Freestyle/Cycles still use every core for the rendering itself.
Spawned workers re-import the caller's `__main__`: scripts that call `draw_collection` with
jobs != 1 need the usual `if __name__ == "__main__":` guard.
"""
from __future__ import annotations

import multiprocessing
import os
import sys
from pathlib import Path
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Callable, Sequence

import numpy as np

from ..cache import CODE_VERSION, DrawingCache, cache_key
from ..drawings import ShapeDrawings
from ..meshes import InputError, Mesh, normalise
from ..params import DrawingSettings
from ..progress import Cancelled  # noqa: F401  (raised here, re-exported for callers)

Progress = Callable[[str, int, int], None]


def in_blender_gui() -> bool:
    """True inside a Blender executable (GUI or `blender -b`), False for the bpy module."""
    import bpy
    return bool(bpy.app.binary_path)


def effective_jobs(jobs: int, n_tasks: int) -> int:
    """How many worker processes to use: 0 = all cores; never more than tasks; 1 in Blender."""
    if in_blender_gui():
        return 1
    if jobs <= 0:
        jobs = os.cpu_count() or 1
    return max(1, min(jobs, n_tasks))


# ---------------------------------------------------------------- worker side
_worker_ready = False


def _worker_init() -> None:
    """Runs once in each spawned worker: a clean factory Blender.

    'spawn' hands the worker the parent's sys.path, which already holds the folders bpy adds
    when imported (its bundled `scripts/modules` has a `bpy` package of its own that shadows the
    real module and fails with "No module named '_bpy'"): drop those before importing bpy.
    """
    global _worker_ready
    sys.path[:] = [p for p in sys.path if "bpy" not in Path(p).parts]
    import bpy
    from .render import quiet_fds
    with quiet_fds():
        bpy.ops.wm.read_factory_settings(use_empty=True)
    _worker_ready = True


def _worker_draw(name: str, vertices: np.ndarray, faces: np.ndarray, settings: DrawingSettings,
                 threads: int) -> dict:
    """Render one normalised mesh in a worker; plain arrays travel back (picklable)."""
    from .render import draw_shape
    return draw_shape(Mesh(name, vertices, faces), settings, threads=threads).to_arrays()


# ---------------------------------------------------------------- parent side
def _describe(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}" if not isinstance(exc, InputError) \
        else (text[0] if text else "bad input")


def draw_collection(meshes: Sequence[Mesh], settings: DrawingSettings, cache_dir=None, jobs: int = 0,
                    progress: Progress | None = None, cancel: Callable[[], bool] | None = None,
                    ) -> tuple[list[ShapeDrawings], list[tuple[str, str]]]:
    """Drawings of every mesh (in input order) and the shapes skipped as (name, reason).

    Meshes are in world space; each is normalised with `settings.up` first. `cache_dir`: a folder,
    None for the default user cache, or False to use no cache. `jobs`: worker processes, 0 = all
    cores, 1 = in this process. `progress(stage, done, total)` with stage 'cache' then 'render';
    `cancel()` is polled between shapes and raises `Cancelled`.
    """
    from .render import draw_shape
    progress = progress or (lambda stage, done, total: None)
    cancel = cancel or (lambda: False)
    cache = DrawingCache(cache_dir) if cache_dir is not False else None

    results: dict[int, ShapeDrawings] = {}
    skipped: dict[int, tuple[str, str]] = {}
    todo: list[tuple[int, Mesh, str | None]] = []
    total = len(meshes)
    for i, raw in enumerate(meshes):
        if cancel():
            raise Cancelled()
        try:
            mesh = normalise(raw, settings.up)
        except InputError as exc:
            skipped[i] = (raw.name, _describe(exc))
            continue
        key = cache_key(mesh, settings, CODE_VERSION) if cache else None
        hit = cache.load(key) if cache else None
        if hit is not None:
            hit.name = raw.name
            results[i] = hit
        else:
            todo.append((i, mesh, key))
        progress("cache", i + 1, total)

    def finish(i: int, key: str | None, drawings: ShapeDrawings) -> None:
        drawings.name = meshes[i].name
        if cache is not None:
            cache.store(key, drawings)
        results[i] = drawings

    n_workers = effective_jobs(jobs, len(todo))
    done = 0
    progress("render", 0, len(todo))
    if n_workers <= 1:
        for i, mesh, key in todo:
            if cancel():
                raise Cancelled()
            try:
                finish(i, key, draw_shape(mesh, settings))
            except Exception as exc:  # one bad shape must not sink the collection
                skipped[i] = (mesh.name, _describe(exc))
            done += 1
            progress("render", done, len(todo))
    else:
        # Cycles threads per worker: share the cores rather than oversubscribe them.
        threads = max(1, (os.cpu_count() or 1) // n_workers)
        ctx = multiprocessing.get_context("spawn")
        pool = ProcessPoolExecutor(max_workers=n_workers, mp_context=ctx, initializer=_worker_init)
        try:
            pending = {pool.submit(_worker_draw, m.name, m.vertices, m.faces, settings, threads): (i, m, k)
                       for i, m, k in todo}
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED, timeout=0.5)
                if cancel():
                    raise Cancelled()
                for fut in finished:
                    i, mesh, key = pending.pop(fut)
                    try:
                        finish(i, key, ShapeDrawings.from_arrays(fut.result()))
                    except Exception as exc:
                        skipped[i] = (mesh.name, _describe(exc))
                    done += 1
                    progress("render", done, len(todo))
        finally:
            pool.shutdown(wait=True, cancel_futures=True)

    order = sorted(results)
    return [results[i] for i in order], [skipped[i] for i in sorted(skipped)]

