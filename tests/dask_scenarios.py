"""Dask scenarios for tests/test_dask.py, run in a process of their own.

Why a separate process: a Dask client leaves threads behind (its event loop, Dask's offload
pool) for the rest of its process, and the test suite checks elsewhere that nothing but the main
thread runs while Blender draws. Prints one line `RESULT <json>`.

    python tests/dask_scenarios.py same|kill SCHEDULER_ADDRESS TMP_DIR
"""
import json
import os
import signal
import sys
import time
from pathlib import Path

import numpy as np
import psutil

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from style_coanalysis import sample  # noqa: E402
from style_coanalysis.blender import batch  # noqa: E402
from style_coanalysis.params import DrawingSettings  # noqa: E402


def same_as_local(remote, shapes, settings) -> bool:
    local, skipped = batch.draw_collection(shapes, settings, cache_dir=False, jobs=1)
    if skipped or [d.name for d in remote] != [d.name for d in local]:
        return False
    return all(np.array_equal(v, b.to_arrays()[k])
               for a, b in zip(remote, local) for k, v in a.to_arrays().items())


def same(address: str, tmp: Path) -> dict:
    shapes = sample.generate(size=6, seed=1)
    settings = DrawingSettings(renderer="lineart")
    events = []
    with batch.use_scheduler(address) as client:
        client.wait_for_workers(2, timeout=120)
        remote, skipped = batch.draw_collection(shapes, settings, cache_dir=tmp / "cache",
                                                progress=lambda *e: events.append(e))
        workers = len(client.scheduler_info()["workers"])
    return {"skipped": skipped, "workers": workers, "n": len(shapes),
            "last_event": list(events[-1][:3]) if events else None,
            "parent_cache": len(list((tmp / "cache").rglob("*.npz"))),
            "same": same_as_local(remote, shapes, settings)}


def kill(address: str, tmp: Path) -> dict:
    """Kill a worker while its Blender process draws; the run must still draw every shape."""
    shapes = sample.generate(size=6, seed=1)
    settings = DrawingSettings(renderer="lineart", seed=7)     # not in the workers' caches yet
    children = []
    with batch.use_scheduler(address) as client:
        client.wait_for_workers(2, timeout=120)
        steps = batch.draw_steps(shapes, settings, cache_dir=False)
        try:
            while not children:
                next(steps)
                pids = client.run(os.getpid)
                for w, keys in client.processing().items():
                    kids = psutil.Process(pids[w]).children() if keys else []
                    if kids:            # its Blender process is up: it is drawing
                        children = kids
                        os.kill(pids[w], signal.SIGKILL)
                        break
            while True:
                next(steps)
        except StopIteration as stop:
            remote, skipped = stop.value
        finally:
            steps.close()
    deadline = time.monotonic() + 30

    def alive():
        return [c for c in children if c.is_running() and c.status() != psutil.STATUS_ZOMBIE]
    while alive() and time.monotonic() < deadline:
        time.sleep(0.5)
    return {"skipped": skipped, "killed_with_blender": len(children), "blender_left": len(alive()),
            "same": same_as_local(remote, shapes, settings)}


if __name__ == "__main__":
    what, address, tmp = sys.argv[1], sys.argv[2], Path(sys.argv[3])
    result = {"same": same, "kill": kill}[what](address, tmp)
    print("RESULT " + json.dumps(result), flush=True)
