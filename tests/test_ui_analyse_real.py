"""The Analyse operator with the real job (no stand-in): same clusters as the headless command,
and a run cancelled part-way leaves nothing behind (issue: the Style side panel)."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

bpy = pytest.importorskip("bpy")
pytestmark = [pytest.mark.blender, pytest.mark.slow]
ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def collection(ext, tmp_path_factory):
    """Ten generated shapes saved as a .blend, and the headless command's report on it."""
    tmp = tmp_path_factory.mktemp("ui_real")
    from style_coanalysis_ext.style_coanalysis.blender import scene
    from style_coanalysis_ext.style_coanalysis.sample import generate
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene.objects_from_meshes(generate(10, seed=5), "Shapes")
    blend = tmp / "shapes.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    res = subprocess.run([sys.executable, "-m", "style_coanalysis", "analyze", str(blend), "--out",
                          str(tmp / "out"), "--renderer", "lineart", "--jobs", "1", "--cache",
                          str(tmp / "cache"), "--rounds", "2"], cwd=ROOT, capture_output=True,
                         text=True, timeout=900)
    assert res.returncode == 0, res.stderr[-3000:]
    report = json.loads((tmp / "out" / "report.json").read_text())
    return blend, {s["name"]: s["cluster"] for s in report["shapes"]}, tmp / "cache", \
        report["dictionary_agreement"]


def prepare(blend, cache):
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    settings = bpy.context.scene.style_coanalysis
    settings.renderer = "lineart"
    settings.max_rounds = 2
    for o in bpy.context.scene.objects:
        o.select_set(o.type == "MESH")
    prefs_cache = str(cache)
    return settings, prefs_cache


def partition(assign: dict) -> set:
    groups = {}
    for name, c in assign.items():
        groups.setdefault(c, set()).add(name)
    return {frozenset(g) for g in groups.values()}


def test_operator_gives_the_same_clusters_as_the_command(collection):
    blend, headless, cache, agreement = collection
    prepare(blend, cache)
    assert bpy.ops.style.analyse() == {"FINISHED"}
    ui = {o.name: o["style_cluster"] for o in bpy.context.scene.objects if "style_cluster" in o}
    assert set(ui) == set(headless)
    assert partition(ui) == partition(headless)
    # the sidebar keeps how firm the clusters are, as the command's report.json has it
    assert "firm" in bpy.context.scene.style_coanalysis.last_report
    assert f"({agreement:.2f})" in bpy.context.scene.style_coanalysis.last_report


def test_cancel_from_the_progress_callback_leaves_nothing_behind(collection, monkeypatch):
    blend, _, cache, _ = collection
    prepare(blend, cache)
    from style_coanalysis_ext.style_coanalysis.blender import job
    real = job.run_steps
    seen = []

    def run_steps(meshes, options):
        # the caller's progress handling asks to stop once the last stage has begun
        options.cancel = lambda: bool(seen) and seen[-1][0] == "localise"
        gen = real(meshes, options)
        while True:
            try:
                step = next(gen)
            except StopIteration as stop:
                return stop.value
            seen.append(step)
            yield step

    monkeypatch.setattr(job, "run_steps", run_steps)
    materials_before = set(bpy.data.materials.keys())
    collections_before = set(bpy.data.collections.keys())
    assert bpy.ops.style.analyse() == {"CANCELLED"}
    assert any(s[0] == "localise" for s in seen), "the job never reached the last stage"
    for o in bpy.context.scene.objects:
        assert "style_weight" not in o.vertex_groups, o.name
        assert not any(k.startswith("style_") for k in o.keys()), o.name
    assert set(bpy.data.materials.keys()) == materials_before
    assert set(bpy.data.collections.keys()) == collections_before
