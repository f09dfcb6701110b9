"""Pure per-shape work in spawned worker processes, results in order.

The drawings need Blender's workers (`blender.batch`); the per-shape work after them (HOG maps,
style regions) is numpy and scikit-image only, and a pure function of its arguments, so it runs
in plain processes and gives the serial result. (The analysis' encoding stays in one process:
its word counts' matrix products already keep every core busy through their threads; its
dictionaries and word counts in 2 processes took 62.8 s against 66.6 s at 1,050 shapes.) Which
number of processes is sensible (none inside Blender's own Python, whose `sys.executable` is not
a Python that can be spawned) is the caller's to decide: `blender.batch.effective_jobs`.

Each worker process gets its share of the cores for its numeric libraries' threads (BLAS,
OpenMP), so N workers on N cores do not start N threads each and fight over them. The
process's own threads are not capped: the analysis' results would then depend in their last
bits on `--jobs` (multi-threaded sums add in another order), which must not change them.
"""
from __future__ import annotations

import collections
import multiprocessing
import os
import signal
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Iterable

_worker_shared: dict = {}
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def core_share(n_workers: int) -> int:
    """Each of n_workers processes' share of this machine's cores (at least 1)."""
    return max(1, (os.cpu_count() or 1) // max(1, int(n_workers)))


def plain_worker_init(shared: dict | None = None, threads: int = 0) -> None:
    """Runs once in each spawned worker, with or without Blender.

    'spawn' hands the worker the parent's sys.path, which already holds the folders bpy adds
    when imported (its bundled `scripts/modules` has a `bpy` package of its own that shadows the
    real module and fails with "No module named '_bpy'"): drop those. Ctrl-C in a terminal
    reaches the whole process group: workers ignore it and the parent, which does get it, ends
    them. `shared`: the keyword arguments every task of `in_processes` has, sent once.
    `threads`: the worker's share of the cores, the cap on its numeric libraries' threads for
    its whole life (0: no cap).
    """
    global _worker_shared
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    sys.path[:] = [p for p in sys.path if "bpy" not in Path(p).parts]
    _worker_shared = dict(shared or {})
    if threads >= 1:
        # libraries loaded later read these when they load; those loaded already are capped
        for var in THREAD_VARIABLES:
            os.environ[var] = str(threads)
        from threadpoolctl import threadpool_limits
        threadpool_limits(limits=threads)


def _call_shared(fn, item: dict):
    """One task of `in_processes` in a worker: fn(**shared, **item)."""
    return fn(**_worker_shared, **item)


def in_processes(fn, items: Iterable[dict], n_items: int, jobs: int, shared: dict | None = None):
    """Generator: `fn(**shared, **item)` for every item (keyword arguments), in their order.

    In min(jobs, n_items) spawned processes, each with its share of the cores (`core_share`), or
    here when that is 1. `fn` is a module-level function; `shared` (a dictionary's words, say)
    is sent to each worker once; `items` is read lazily, at most two per worker in flight, so a
    large collection is never pickled at once. Closing the generator (a cancel) ends the
    workers at once.
    """
    items = iter(items)
    n_workers = max(1, min(int(jobs), int(n_items)))
    if n_workers <= 1:
        for item in items:
            yield fn(**(shared or {}), **item)
        return
    pool = ProcessPoolExecutor(max_workers=n_workers,
                               mp_context=multiprocessing.get_context("spawn"),
                               initializer=plain_worker_init,
                               initargs=(shared, core_share(n_workers)))
    ok = False
    try:
        pending: collections.deque = collections.deque()
        for item in items:
            pending.append(pool.submit(_call_shared, fn, item))
            if len(pending) >= 2 * n_workers:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()
        ok = True
    finally:
        end_pool(pool, now=not ok)


def end_pool(pool: ProcessPoolExecutor, now: bool) -> None:
    """Shut a pool down; `now`: terminate its workers instead of letting them finish."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    if not now:
        pool.shutdown(wait=True, cancel_futures=True)
        return
    for p in procs:
        if p.is_alive():
            p.terminate()
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        p.join(timeout=5)
        if p.is_alive():
            p.kill()
