"""Per-shape drawing on a Dask distributed cluster (`--scheduler ADDRESS`): beyond one machine.

Why Dask: an existing engine schedules the shapes, moves their arrays and, when a worker dies,
reruns the shapes it held on another worker (the scheduler's own fault tolerance), so this module
only says what one task is. Dask is optional: only the command line imports this module, when it
is given a scheduler; the extension zip never bundles Dask (it is not in requirements.txt).

- The parent checks its own drawing cache first and ships only the missing shapes, as their
  normalised arrays (workers need no shared file system), then stores what comes back: the same
  drawings, in the same order, as a local run.
- Each Dask worker keeps Blender in child processes of its own, one per worker thread (bpy runs
  on a process's main thread, never on Dask's task threads, and a Blender crash kills only that
  child: its shape fails once and is retried, as in a local run), and its own drawing cache (the
  worker machine's default, `$XDG_CACHE_HOME/style_coanalysis`).
- Dask's worker processes are daemonic by default and so may not start children: workers must
  run with `DASK_DISTRIBUTED__WORKER__DAEMON=False` (checked when connecting).
"""
from __future__ import annotations

import contextlib
import multiprocessing
import os
import threading
import time
from concurrent.futures.process import BrokenProcessPool, ProcessPoolExecutor

import numpy as np
from distributed import Client, WorkerPlugin, get_worker

from ..cache import DrawingCache, cache_key
from ..parallel import end_pool
from ..drawings import ShapeDrawings
from ..meshes import InputError, Mesh
from . import batch

PLUGIN = "style-coanalysis-blender"
CONNECT_TIMEOUT_S = 10
WORKER_WAIT_S = 30          # a scheduler with no worker yet: how long to wait for the first one
RETRIES = 1                 # a shape whose Blender process crashed is tried once more
DAEMONIC = ("a daemonic process cannot start Blender: start Dask workers with "
            "DASK_DISTRIBUTED__WORKER__DAEMON=False")


# ---------------------------------------------------------------- parent side
@contextlib.contextmanager
def use_scheduler(address: str):
    """`batch.use_scheduler`'s Dask half: connects at once (a bad address is refused before
    anything is loaded or drawn) and closes the client after the block."""
    client = connect(address)
    token = batch.cluster.set(client)
    try:
        yield client
    finally:
        batch.cluster.reset(token)
        client.close()


def connect(address: str) -> Client:
    """A client of the scheduler at `address`, its workers checked and given the Blender plugin."""
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(f"cannot reach the Dask scheduler at '{address}': "
                         f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from None
    try:
        try:
            client.wait_for_workers(1, timeout=WORKER_WAIT_S)
        except TimeoutError:
            raise InputError(f"the Dask scheduler at '{address}' has no worker (waited "
                             f"{WORKER_WAIT_S} s): start some with 'dask worker {address}'") from None
        try:        # the scheduler unpickles tasks and the workers run them: both import us
            client.submit(_is_daemonic, pure=False).result(timeout=WORKER_WAIT_S)
            daemonic = [w for w, d in client.run(_is_daemonic).items() if d]
        except Exception as exc:
            text = str(exc).strip().splitlines()
            raise InputError(f"the Dask cluster at '{address}' cannot run the drawing: "
                             f"{type(exc).__name__}: {text[0] if text else ''} (the scheduler and "
                             "every worker need this repository on their PYTHONPATH, see README)"
                             ) from None
        if daemonic:
            raise InputError(f"Dask worker(s) {', '.join(sorted(daemonic))}: {DAEMONIC}")
        client.register_plugin(BlenderWorkers(), name=PLUGIN)
    except BaseException:
        client.close()
        raise
    return client


def _is_daemonic() -> bool:
    return bool(multiprocessing.current_process().daemon)


def render_on_cluster(client: Client, todo, settings, finish, skipped):
    """Generator for `batch.draw_steps`: draw `todo` ((index, normalised mesh, key) items) on
    the cluster; `finish(i, key, drawings)` per shape, failures into `skipped`; yields progress.

    Closing it (a cancel, Ctrl-C) cancels the shapes not drawn yet."""
    futures = {}
    for item in todo:
        _, m, key = item
        fut = client.submit(draw_task, m.name, m.vertices, m.faces, settings, pure=False,
                            retries=RETRIES)
        futures[fut] = item
    done, total, detail = 0, len(todo), None
    try:
        pending = set(futures)
        while pending:
            finished = {f for f in pending if f.done()}
            if not finished:
                time.sleep(batch.WAIT_S)
            pending -= finished
            for fut in finished:
                i, mesh, key = futures[fut]
                try:
                    finish(i, key, ShapeDrawings.from_arrays(fut.result()))
                    detail = f"'{mesh.name}' drawn on the cluster"
                except Exception as exc:  # one bad shape must not sink the collection
                    skipped[i] = (mesh.name, batch._describe(exc))
                done += 1
            yield ("render", done, total, detail)
    finally:
        client.cancel([f for f in futures if not f.done()])


# ---------------------------------------------------------------- worker side
def draw_task(name: str, vertices: np.ndarray, faces: np.ndarray, settings) -> dict:
    """One shape on a Dask worker (a normalised mesh in, `ShapeDrawings.to_arrays()` out)."""
    return get_worker().plugins[PLUGIN].draw(name, vertices, faces, settings)


def _blender_init(parent_pid: int) -> None:
    """A Blender child of a Dask worker: as a local worker, and it ends if the worker dies
    (a killed worker must not leave Blender processes behind)."""
    batch._worker_init(None)

    def watch():
        while os.getppid() == parent_pid:
            time.sleep(1.0)
        os._exit(1)
    threading.Thread(target=watch, daemon=True).start()


class BlenderWorkers(WorkerPlugin):
    """Held by each Dask worker: its Blender processes (one per worker thread) and its cache."""

    def __init__(self, cache_dir: str | None = None):
        self.cache_dir = cache_dir

    def setup(self, worker) -> None:
        self.slots = max(1, int(worker.state.nthreads))
        self.cache = DrawingCache(self.cache_dir)   # None: this machine's default cache
        self.pool = None
        self.lock = threading.Lock()

    def teardown(self, worker) -> None:
        with self.lock:
            if self.pool is not None:
                end_pool(self.pool, now=True)
                self.pool = None

    def _pool(self) -> ProcessPoolExecutor:
        if _is_daemonic():      # a worker started (or restarted) without the setting
            raise RuntimeError(DAEMONIC)
        with self.lock:
            if self.pool is None:
                self.pool = ProcessPoolExecutor(
                    self.slots, mp_context=multiprocessing.get_context("spawn"),
                    initializer=_blender_init, initargs=(os.getpid(),))
            return self.pool

    def draw(self, name: str, vertices, faces, settings) -> dict:
        key = cache_key(Mesh(name, vertices, faces), settings, batch.drawing_version(settings))
        hit = self.cache.load(key)
        if hit is not None:
            hit.name = name
            return hit.to_arrays()
        pool = self._pool()
        try:
            # one Cycles thread: the worker's threads are its parallelism, as with local jobs
            arrays = pool.submit(batch._worker_draw, name, vertices, faces, settings, 1).result()
        except BrokenProcessPool:
            with self.lock:
                if self.pool is pool:
                    self.pool = None
            end_pool(pool, now=True)
            raise RuntimeError("Blender stopped while drawing it (its process crashed)") from None
        self.cache.store(key, ShapeDrawings.from_arrays(arrays))
        return arrays
