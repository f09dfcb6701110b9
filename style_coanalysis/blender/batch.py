"""Drawings for a whole collection: normalise, use the cache, render the rest.

Per-shape work is a pure function of (normalised mesh, settings) (DESIGN.md), so uncached shapes
go to worker processes and every result is cached by the parent (one writer per entry).

Where rendering happens is decided first, and bpy never runs off the main thread:
- With Blender as a Python module (`bpy.app.binary_path == ""`, tests and the command line) and
  jobs > 1, `sys.executable` is the venv's Python, which can import bpy: workers are started with
  multiprocessing's 'spawn' method and each imports bpy and resets to factory settings itself.
  The parent only waits for them (no thread), so Ctrl-C or a cancel stops them at once. A worker
  that dies (a crash in Blender) costs its shape one retry in a fresh worker of its own; only a
  shape that fails twice is skipped.
- Inside Blender (GUI or `blender -b`), `sys.executable` is Blender's bundled Python, which cannot
  import bpy: there, and with jobs=1, shapes render in this process on the calling (main) thread,
  in steps of one view (`render.draw_shape_steps`), so the modal operator keeps the UI responsive.
  Freestyle/Cycles still use every core for the rendering itself.
- Inside `dask_cluster.use_scheduler(address)` (the command line's `--scheduler`), uncached
  shapes are drawn on that Dask cluster instead, and `jobs` is not used (`dask_cluster`).
Spawned workers re-import the caller's `__main__`: scripts that call `draw_collection` with
jobs != 1 need the usual `if __name__ == "__main__":` guard.
"""
from __future__ import annotations

import contextlib
import contextvars
import multiprocessing
import os
import queue as queue_module
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Callable, Sequence

import numpy as np

from ..cache import CODE_VERSION, DrawingCache, cache_key
from ..drawings import ShapeDrawings
from ..meshes import InputError, Mesh, normalise
from ..parallel import core_share, end_pool, plain_worker_init
from ..params import DrawingSettings
from ..progress import Cancelled

Progress = Callable[[str, int, int], None]
WAIT_S = 0.1                # the parent's poll interval while workers render
IN_HAND = 2                 # shapes submitted per worker: its next one waits while it draws
# The Dask client of the enclosing `dask_cluster.use_scheduler` block: a context rather than an
# argument, so the job and its options need not know about Dask (an optional dependency).
cluster: contextvars.ContextVar = contextvars.ContextVar("style_coanalysis_cluster", default=None)


@contextlib.contextmanager
def use_scheduler(address: str | None):
    """Within the block, uncached shapes are drawn on the Dask cluster at `address` (None or "":
    here, as `jobs` says). Dask is imported only when an address is given."""
    if not address:
        yield None
        return
    try:
        from . import dask_cluster
    except ImportError as exc:
        raise InputError(f"--scheduler needs Dask on this machine ({exc}): pip install "
                         "'dask[distributed]' (README: running on many machines)") from None
    with dask_cluster.use_scheduler(address) as client:
        yield client


def drawing_version(settings: DrawingSettings) -> str:
    """The code version in a drawing's cache key: the zbuffer renderer has one of its own, so
    changing it leaves the other renderers' cache entries valid."""
    if settings.renderer == "zbuffer":
        from ..zbuffer import VERSION
        return f"{CODE_VERSION}+{VERSION}"
    return CODE_VERSION


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
_worker_queue = None


def _worker_init(progress_queue=None, threads: int = 0) -> None:
    """Runs once in each spawned drawing worker: `parallel.plain_worker_init` (its numeric
    libraries capped at `threads`, its share of the cores), then a clean factory Blender."""
    global _worker_ready, _worker_queue
    plain_worker_init(threads=threads)
    _worker_queue = progress_queue
    import bpy
    from .render import quiet_fds
    with quiet_fds():
        bpy.ops.wm.read_factory_settings(use_empty=True)
    _worker_ready = True


def _worker_draw(name: str, vertices: np.ndarray, faces: np.ndarray, settings: DrawingSettings,
                 threads: int) -> dict:
    """Render one normalised mesh in a worker; plain arrays travel back (picklable). Each step
    (a view) is reported to the parent through the progress queue."""
    from .render import draw_shape_steps
    steps = draw_shape_steps(Mesh(name, vertices, faces), settings, threads=threads)
    while True:
        try:
            detail = next(steps)
        except StopIteration as stop:
            return stop.value.to_arrays()
        if _worker_queue is not None:
            try:
                _worker_queue.put_nowait((name, detail))
            except Exception:  # progress is best effort
                pass


# ---------------------------------------------------------------- parent side
def _describe(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}" if not isinstance(exc, InputError) \
        else (text[0] if text else "bad input")


def draw_collection(meshes: Sequence[Mesh], settings: DrawingSettings, cache_dir=None, jobs: int = 0,
                    progress: Progress | None = None, cancel: Callable[[], bool] | None = None,
                    worker=None) -> tuple[list[ShapeDrawings], list[tuple[str, str]]]:
    """Drawings of every mesh (in input order) and the shapes skipped as (name, reason).

    `draw_steps` run to its end: `progress(stage, done, total)` at every step, `cancel()` polled
    at every step (raises `Cancelled`).
    """
    progress = progress or (lambda stage, done, total: None)
    cancel = cancel or (lambda: False)
    steps = draw_steps(meshes, settings, cache_dir, jobs, worker=worker)
    try:
        while True:
            try:
                step = next(steps)
            except StopIteration as stop:
                return stop.value
            progress(*step[:3])
            if cancel():
                raise Cancelled()
    finally:
        steps.close()


def draw_steps(meshes: Sequence[Mesh], settings: DrawingSettings, cache_dir=None, jobs: int = 0,
               worker=None):
    """Generator: yields (stage, done, total, detail) steps; returns (drawings, skipped).

    Meshes are in world space; each is normalised with `settings.up` first. `cache_dir`: a folder,
    None for the default user cache, or False to use no cache. `jobs`: worker processes, 0 = all
    cores, 1 = in this process. Stage 'cache' then 'render' (detail: the shape and its view).
    Closing the generator (a cancel, Ctrl-C) ends the workers at once. `worker`: the function a
    worker process runs per shape (tests substitute one that crashes).
    """
    cache = DrawingCache(cache_dir) if cache_dir is not False else None
    results: dict[int, ShapeDrawings] = {}
    skipped: dict[int, tuple[str, str]] = {}
    todo: list[tuple[int, Mesh, str | None]] = []
    total = len(meshes)
    for i, raw in enumerate(meshes):
        try:
            mesh = normalise(raw, settings.up)
        except InputError as exc:
            skipped[i] = (raw.name, _describe(exc))
            continue
        key = cache_key(mesh, settings, drawing_version(settings)) if cache else None
        hit = cache.load(key) if cache else None
        if hit is not None:
            hit.name = raw.name
            results[i] = hit
        else:
            todo.append((i, mesh, key))
        yield ("cache", i + 1, total, None)

    def finish(i: int, key: str | None, drawings: ShapeDrawings) -> None:
        drawings.name = meshes[i].name
        if cache is not None:
            cache.store(key, drawings)
        results[i] = drawings

    n_workers = effective_jobs(jobs, len(todo))
    yield ("render", 0, len(todo), None)
    client = cluster.get()
    if client is not None and todo:
        from .dask_cluster import render_on_cluster
        yield from render_on_cluster(client, todo, settings, finish, skipped)
    elif n_workers <= 1:
        from .render import draw_shape_steps
        for done, (i, mesh, key) in enumerate(todo):
            steps = draw_shape_steps(mesh, settings)
            try:
                while True:
                    try:
                        detail = next(steps)
                    except StopIteration as stop:
                        finish(i, key, stop.value)
                        break
                    yield ("render", done, len(todo), f"'{mesh.name}' {detail}")
            except Exception as exc:  # one bad shape must not sink the collection
                skipped[i] = (mesh.name, _describe(exc))
            finally:
                steps.close()
            yield ("render", done + 1, len(todo), None)
    else:
        yield from _render_in_workers(todo, settings, n_workers, finish, skipped,
                                      worker or _worker_draw)

    order = sorted(results)
    return [results[i] for i in order], [skipped[i] for i in sorted(skipped)]


def _render_in_workers(todo, settings, n_workers, finish, skipped, worker):
    """Generator: render `todo` in spawned worker processes, n_workers shapes at a time.

    Each worker has its next shape in hand (`IN_HAND` submitted per worker), so it never waits
    for the parent to store a finished shape and hand it another: on the zbuffer path, where a
    shape takes about 0.15 s, that wait was 10-20% of the drawing step (300 sample shapes, 2
    workers: 24.3 / 21.6 s with one shape per worker, 19.6 / 19.5 s with two).
    A worker that dies breaks its pool: the shapes the pool had in hand each get one retry alone
    in a fresh worker (alone, so a second crash is surely theirs); a shape whose retry dies too
    is skipped with the reason. The other shapes carry on in a new pool.
    """
    threads = core_share(n_workers)    # Cycles' and numpy's threads: never oversubscribe
    ctx = multiprocessing.get_context("spawn")
    progress_queue = ctx.Queue()
    waiting = list(todo)        # not started yet
    retries: list = []          # were rendering when a worker died: one retry each, alone
    done, total = 0, len(todo)
    detail = None               # the latest view a worker reported
    try:
        while waiting or retries:
            alone = bool(retries)
            group = [retries.pop(0)] if alone else waiting
            if not alone:
                waiting = []
            width = 1 if alone else n_workers
            depth = 1 if alone else IN_HAND
            pool = ProcessPoolExecutor(max_workers=width, mp_context=ctx, initializer=_worker_init,
                                       initargs=(progress_queue, threads))
            running: dict = {}
            ok = False
            try:
                while group or running:
                    while group and len(running) < width * depth:
                        item = group.pop(0)
                        _, m, _ = item
                        running[pool.submit(worker, m.name, m.vertices, m.faces, settings,
                                            threads)] = item
                    finished, _ = wait(running, timeout=WAIT_S, return_when=FIRST_COMPLETED)
                    while True:
                        try:
                            name, what = progress_queue.get_nowait()
                            detail = f"'{name}' {what}"
                        except (queue_module.Empty, OSError, EOFError, ValueError):
                            break
                    broken = False
                    for fut in finished:
                        i, mesh, key = running.pop(fut)
                        try:
                            finish(i, key, ShapeDrawings.from_arrays(fut.result()))
                        except BrokenProcessPool:
                            broken = True
                            running[fut] = (i, mesh, key)
                            continue
                        except Exception as exc:
                            skipped[i] = (mesh.name, _describe(exc))
                        done += 1
                    if broken:
                        for i, mesh, key in running.values():
                            if alone:
                                skipped[i] = (mesh.name, "its drawing worker crashed twice "
                                              "(Blender stopped while drawing it)")
                                done += 1
                            else:
                                retries.append((i, mesh, key))
                        running.clear()
                        waiting = group + waiting   # the rest goes on in a fresh pool
                        group = []
                        break
                    yield ("render", done, total, detail)
                ok = True
            finally:
                end_pool(pool, now=not ok)
            yield ("render", done, total, None)
    finally:
        progress_queue.close()
        progress_queue.cancel_join_thread()
