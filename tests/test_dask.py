"""Drawing on a real Dask cluster (`--scheduler`): a LocalCluster of 2 worker processes.

The same drawings and the same partition as a local run; a worker killed while it draws has its
shapes drawn elsewhere and leaves no Blender process behind; a bad address is refused before any
drawing; Dask is never part of what the extension zip bundles.
"""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
pytestmark = [pytest.mark.blender, pytest.mark.slow]


def run_cmd(*args, timeout=900):
    return subprocess.run([sys.executable, "-m", "style_coanalysis", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


def test_dask_is_not_bundled_nor_imported_without_a_scheduler():
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        import build_dist
    finally:
        sys.path.remove(str(ROOT / "tools"))
    bundled = [r.split("==")[0].lower() for r in build_dist.runtime_requirements()]
    assert bundled and not {"dask", "distributed"} & set(bundled)
    code = ("import sys, style_coanalysis.cli, style_coanalysis.blender.batch, "
            "style_coanalysis.blender.job; print(sorted(m for m in sys.modules "
            "if m.split('.')[0] in ('dask', 'distributed')))")
    res = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.strip() == "[]"


def test_unreachable_scheduler_is_refused_before_drawing(tmp_path):
    pytest.importorskip("distributed")
    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\n"
                                    "f 2 4 3\n")
    res = run_cmd("render", folder, "--out", tmp_path / "out", "--scheduler", "tcp://127.0.0.1:9",
                  "--cache", tmp_path / "cache", timeout=120)
    assert res.returncode == 2, res.stderr[-2000:]
    assert "cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'" in res.stderr
    assert not (tmp_path / "out").exists() and not (tmp_path / "cache").exists()


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """2 worker processes, 1 thread each, with their own drawing cache (XDG_CACHE_HOME)."""
    dask = pytest.importorskip("dask")
    distributed = pytest.importorskip("distributed")
    worker_home = tmp_path_factory.mktemp("worker_cache")
    # for the whole cluster's life: the nanny reads it again when it restarts a killed worker
    with dask.config.set({"distributed.worker.daemon": False}):
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=None, host="127.0.0.1",
                                      env={"XDG_CACHE_HOME": str(worker_home)}) as cl:
            yield cl, worker_home


@pytest.fixture(scope="module")
def shapes():
    from style_coanalysis import sample
    return sample.generate(size=6, seed=1)


def local_drawings(shapes, settings):
    from style_coanalysis.blender import batch
    drawings, skipped = batch.draw_collection(shapes, settings, cache_dir=False, jobs=1)
    assert not skipped
    return drawings


def assert_same(a, b):
    assert [d.name for d in a] == [d.name for d in b]
    for x, y in zip(a, b):
        for k, v in x.to_arrays().items():
            assert np.array_equal(v, y.to_arrays()[k]), (x.name, k)


def test_cluster_draws_what_a_local_run_draws(cluster, shapes, tmp_path):
    from style_coanalysis.blender import batch
    from style_coanalysis.params import DrawingSettings
    cl, worker_home = cluster
    s = DrawingSettings(renderer="lineart")
    events = []
    with batch.use_scheduler(cl.scheduler_address) as client:
        remote, skipped = batch.draw_collection(shapes, s, cache_dir=tmp_path / "cache",
                                                progress=lambda *e: events.append(e))
        ran_on = set(client.scheduler_info()["workers"])
    assert not skipped and len(ran_on) == 2
    assert ("render", len(shapes), len(shapes)) in events
    assert_same(remote, local_drawings(shapes, s))
    # every shape is in the parent's cache and in a worker's own cache
    worker_entries = list((worker_home / "style_coanalysis").rglob("*.npz"))
    assert len(list((tmp_path / "cache").rglob("*.npz"))) == len(shapes)
    assert len(worker_entries) == len(shapes)


def test_analysis_on_the_cluster_gives_the_local_partition(cluster, tmp_path):
    cl, _ = cluster
    res = run_cmd("sample", "--out", tmp_path / "sample", "--size", 12, "--seed", 3)
    assert res.returncode == 0, res.stderr[-3000:]
    reports = {}
    for how, extra in (("local", ["--jobs", 2]), ("dask", ["--scheduler", cl.scheduler_address])):
        out = tmp_path / how / "result"
        res = run_cmd("analyze", tmp_path / "sample" / "sample.blend", "--out", out,
                      "--renderer", "lineart", "--cache", tmp_path / how / "cache", "--rounds", 2,
                      *extra)
        assert res.returncode == 0, res.stderr[-3000:]
        reports[how] = json.loads((out / "report.json").read_text())
    clusters = {how: {s["name"]: s["cluster"] for s in r["shapes"]} for how, r in reports.items()}
    assert len(clusters["local"]) == 12
    assert clusters["dask"] == clusters["local"]
    assert reports["dask"]["clusters"] == reports["local"]["clusters"]


def test_a_killed_worker_s_shapes_are_drawn_elsewhere(cluster, shapes, tmp_path):
    psutil = pytest.importorskip("psutil")
    from style_coanalysis.blender import batch
    from style_coanalysis.params import DrawingSettings
    cl, _ = cluster
    s = DrawingSettings(renderer="lineart", seed=7)     # not in the workers' caches yet
    with batch.use_scheduler(cl.scheduler_address) as client:
        steps = batch.draw_steps(shapes, s, cache_dir=False)
        victim, blender_children = None, []
        try:
            while victim is None:
                next(steps)
                busy = {w: keys for w, keys in client.processing().items() if keys}
                pids = client.run(os.getpid)
                for w in busy:
                    children = psutil.Process(pids[w]).children()
                    if children:            # its Blender process is up: it is drawing
                        victim, blender_children = w, children
                        os.kill(pids[w], signal.SIGKILL)
                        break
            while True:
                next(steps)
        except StopIteration as stop:
            remote, skipped = stop.value
        finally:
            steps.close()
    assert not skipped, skipped
    assert_same(remote, local_drawings(shapes, s))
    # the killed worker's Blender processes noticed and ended
    deadline = time.monotonic() + 30
    while any(c.is_running() and c.status() != psutil.STATUS_ZOMBIE for c in blender_children) \
            and time.monotonic() < deadline:
        time.sleep(0.5)
    assert not any(c.is_running() and c.status() != psutil.STATUS_ZOMBIE
                   for c in blender_children)
