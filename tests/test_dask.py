"""Drawing on a real Dask cluster (`--scheduler`): a scheduler and 2 worker processes on this
machine, started with the README's `dask scheduler` / `dask worker` commands.

The same drawings and the same partition as a local run; a worker killed while it draws has its
shapes drawn elsewhere and leaves no Blender process behind; a bad address is refused before any
drawing; Dask is never part of what the extension zip bundles. The Dask client runs in
subprocesses (`dask_scenarios.py`, the command line): it leaves threads in its process.
"""
import importlib.util
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
pytestmark = [pytest.mark.blender, pytest.mark.slow]
# found, not imported: no Dask in this process (see the module docstring)
needs_dask = pytest.mark.skipif(importlib.util.find_spec("distributed") is None,
                                reason="Dask (dask[distributed]) is not installed")


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


@needs_dask
def test_unreachable_scheduler_is_refused_before_drawing(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\n"
                                    "f 2 4 3\n")
    res = run_cmd("render", folder, "--out", tmp_path / "out", "--scheduler", "tcp://127.0.0.1:9",
                  "--cache", tmp_path / "cache", timeout=120)
    assert res.returncode == 2, res.stderr[-2000:]
    assert "cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'" in res.stderr
    assert not (tmp_path / "out").exists() and not (tmp_path / "cache").exists()


def start(args: list[str], env: dict, log: Path) -> subprocess.Popen:
    bindir = Path(sys.executable).parent
    return subprocess.Popen([str(bindir / "dask"), *args], cwd=ROOT, env=env,
                            stdout=log.open("w"), stderr=subprocess.STDOUT)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """The README's cluster on this machine: `dask scheduler` and `dask worker --nworkers 2
    --nthreads 1`, with the repository on PYTHONPATH and their own drawing cache (XDG_CACHE_HOME).
    Separate processes: no Dask client or thread in this test process."""
    if importlib.util.find_spec("distributed") is None:
        pytest.skip("Dask (dask[distributed]) is not installed")
    tmp = tmp_path_factory.mktemp("cluster")
    env = dict(os.environ, PYTHONPATH=str(ROOT), DASK_DISTRIBUTED__WORKER__DAEMON="False",
               XDG_CACHE_HOME=str(tmp / "worker_cache"))
    file = tmp / "scheduler.json"
    procs = [start(["scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                    "--scheduler-file", str(file)], env, tmp / "scheduler.log")]
    try:
        deadline = time.monotonic() + 120
        while not file.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        assert file.exists(), (tmp / "scheduler.log").read_text()[-2000:]
        procs.append(start(["worker", "--scheduler-file", str(file), "--nworkers", "2",
                            "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard"], env,
                           tmp / "worker.log"))
        yield json.loads(file.read_text())["address"], tmp / "worker_cache"
    finally:
        for p in reversed(procs):       # workers first, then the scheduler
            p.terminate()
            try:
                p.wait(timeout=60)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def scenario(what: str, address: str, tmp: Path) -> dict:
    res = subprocess.run([sys.executable, str(ROOT / "tests" / "dask_scenarios.py"), what, address,
                          str(tmp)], cwd=ROOT, capture_output=True, text=True, timeout=900)
    lines = [line for line in res.stdout.splitlines() if line.startswith("RESULT ")]
    assert res.returncode == 0 and lines, res.stderr[-3000:]
    return json.loads(lines[-1][7:])


def test_cluster_draws_what_a_local_run_draws(cluster, tmp_path):
    address, worker_cache = cluster
    r = scenario("same", address, tmp_path)
    assert r["skipped"] == [] and r["workers"] == 2
    assert r["last_event"] == ["render", r["n"], r["n"]]
    assert r["same"]                                    # every array equal to the local run's
    # every shape is in the parent's cache and in a worker's own cache
    assert r["parent_cache"] == r["n"]
    assert len(list((worker_cache / "style_coanalysis").rglob("*.npz"))) == r["n"]


def test_analysis_on_the_cluster_gives_the_local_partition(cluster, tmp_path):
    address, _ = cluster
    res = run_cmd("sample", "--out", tmp_path / "sample", "--size", 12, "--seed", 3)
    assert res.returncode == 0, res.stderr[-3000:]
    reports = {}
    for how, extra in (("local", ["--jobs", 2]), ("dask", ["--scheduler", address])):
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


def test_a_killed_worker_s_shapes_are_drawn_elsewhere(cluster, tmp_path):
    address, _ = cluster
    r = scenario("kill", address, tmp_path)
    assert r["killed_with_blender"] >= 1        # the worker was killed while Blender drew
    assert r["skipped"] == [] and r["same"]     # yet every shape was drawn, as locally
    assert r["blender_left"] == 0               # and its Blender processes ended with it
