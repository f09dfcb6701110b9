"""The headless command end to end, as a pipeline script would run it (issue: main job).

Real parts only: the sample generator writes a .blend, the command renders real line drawings
(Line Art, the fast renderer, to keep the suite short), analyses, writes back and saves.
"""
import hashlib
import json
import subprocess
import sys
from pathlib import Path

import pytest
from bad_blend import write_blend_with_bad_vertex

ROOT = Path(__file__).resolve().parent.parent
pytestmark = [pytest.mark.blender, pytest.mark.slow]


def run_cmd(*args, timeout=900):
    return subprocess.run([sys.executable, "-m", "style_coanalysis", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


def digest(folder: Path) -> dict:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def blend_state(path: Path) -> dict:
    """What a result.blend holds, read in a fresh process."""
    code = f"""
import bpy, json
bpy.ops.wm.open_mainfile(filepath={str(path)!r})
objs = {{}}
for o in bpy.data.objects:
    if o.type != 'MESH':
        continue
    objs[o.name] = dict(groups=[g.name for g in o.vertex_groups],
                        materials=[m.name if m else None for m in o.data.materials],
                        cluster=o.get('style_cluster'), best_view=o.get('style_best_view'),
                        confidence=o.get('style_confidence'),
                        collections=sorted(c.name for c in o.users_collection))
print('STATE' + json.dumps(dict(objects=objs, n_materials=len(bpy.data.materials),
      collections=sorted(c.name for c in bpy.data.collections))))
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    line = [l for l in res.stdout.splitlines() if l.startswith("STATE")]
    assert line, res.stderr[-2000:]
    return json.loads(line[-1][5:])


@pytest.fixture(scope="module")
def sample(tmp_path_factory):
    out = tmp_path_factory.mktemp("sample")
    res = run_cmd("sample", "--out", out, "--size", 16, "--seed", 3)
    assert res.returncode == 0, res.stderr[-3000:]
    return out


@pytest.fixture(scope="module")
def first_run(sample, tmp_path_factory):
    out = tmp_path_factory.mktemp("run1") / "result"
    before = digest(sample)
    res = run_cmd("analyze", sample / "sample.blend", "--out", out, "--renderer", "lineart",
                  "--jobs", 2, "--cache", out.parent / "cache", "--rounds", 2)
    assert res.returncode == 0, res.stderr[-3000:]
    assert digest(sample) == before, "the input files were modified"
    return out, res


def test_report_json_has_what_users_read(first_run, sample):
    out, res = first_run
    rep = json.loads((out / "report.json").read_text())
    assert {"parameters", "seconds", "shapes", "clusters"} <= rep.keys()
    assert rep["parameters"]["analysis"]["eta"] == 0.2 and rep["parameters"]["analysis"]["mu"] == 0.07
    names = {l.split(",")[0] for l in (sample / "labels.csv").read_text().splitlines()[1:]}
    assert {s["name"] for s in rep["shapes"]} == names
    for s in rep["shapes"]:
        assert {"name", "source", "cluster", "label", "label_given", "confidence",
                "style_vertex_fraction", "best_view"} <= s.keys()
        assert 0 <= s["best_view"] < 12 and 0.0 <= s["style_vertex_fraction"] <= 1.0
    assert sum(c["size"] for c in rep["clusters"]) == len(rep["shapes"])
    assert {"purity", "nmi", "ari"} <= rep["scores"]["style"].keys()  # the sample carries truth
    assert rep["seconds"]["render"] > 0 and rep["seconds"]["total"] >= rep["seconds"]["render"]
    html = (out / "report.html").read_text()
    assert html.count("<figure>") == len(rep["shapes"])
    assert all((out / "images" / f"{s['name']}_lines.png").is_file() for s in rep["shapes"])
    assert "render" in res.stderr and "/16" in res.stderr   # progress went to stderr
    # no --clusters: the number was chosen from the data, and the user is told the runner-up
    auto = rep["automatic_k"]
    gaps = {int(k): g for k, g in auto["gaps"].items()}
    assert set(gaps) == {2, 3, 4}                            # 2 .. N/4 for 16 shapes
    assert auto["chosen"] == len(rep["clusters"]) == max(gaps, key=gaps.get)
    assert "next likeliest is" in res.stderr and "next likeliest is" in html
    # unsupervised: how firmly the drawings hold the clusters, in the report and on stderr
    assert -1 <= rep["dictionary_agreement"] <= 1
    assert "The clusters are" in res.stderr and "The clusters are" in html


def test_result_blend_carries_results_on_every_mesh(first_run):
    out, _ = first_run
    state = blend_state(out / "result.blend")
    assert len(state["objects"]) == 16
    for name, o in state["objects"].items():
        assert "style_weight" in o["groups"], name
        assert o["cluster"] is not None and 0 <= o["best_view"] < 12
        assert any(c.startswith("Style Cluster") for c in o["collections"]), name


def test_second_run_on_its_own_result_changes_nothing_structurally(first_run, tmp_path):
    out, _ = first_run
    # the drawing cache's entries (`<key[:2]>/<key>.npz` at its top; HOG maps, analyses and
    # regions have folders of their own), each with the time it was written
    drawn = lambda: {p.name: p.stat().st_mtime_ns
                     for p in (out.parent / "cache").glob("[0-9a-f][0-9a-f]/*.npz")}
    before = drawn()
    res = run_cmd("analyze", out / "result.blend", "--out", tmp_path / "again", "--renderer", "lineart",
                  "--jobs", 2, "--cache", out.parent / "cache", "--rounds", 2)
    assert res.returncode == 0, res.stderr[-3000:]
    a, b = blend_state(out / "result.blend"), blend_state(tmp_path / "again" / "result.blend")
    assert a["collections"] == b["collections"] and a["n_materials"] == b["n_materials"]
    for name in a["objects"]:
        assert a["objects"][name]["groups"] == b["objects"][name]["groups"]
        assert a["objects"][name]["materials"] == b["objects"][name]["materials"]
    # the drawings were all cached by the first run: nothing was drawn or written again
    assert len(before) >= 16 and drawn() == before


# ---- bad input: exit 2, a message naming the file or object, inputs untouched ----------------

def write_obj(path: Path, verts, faces=()):
    lines = [f"v {x} {y} {z}" for x, y, z in verts] + [
        "f " + " ".join(str(i + 1) for i in f) for f in faces]
    path.write_text("\n".join(lines) + "\n")


CUBE_V = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
CUBE_F = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]


def expect_refusal(args, *needles, inputs: Path | None = None):
    before = digest(inputs) if inputs else None
    res = run_cmd(*args)
    assert res.returncode == 2, (res.returncode, res.stderr[-2000:])
    for n in needles:
        assert n in res.stderr, (n, res.stderr[-2000:])
    assert "Traceback" not in res.stderr
    if inputs:
        assert digest(inputs) == before
    return res


def test_missing_input(tmp_path):
    expect_refusal(["analyze", tmp_path / "nope.blend", "--out", tmp_path / "o"], "nope.blend")


def test_folder_without_meshes(tmp_path):
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "readme.txt").write_text("no meshes here")
    expect_refusal(["analyze", tmp_path / "in", "--out", tmp_path / "o"], "no mesh", inputs=tmp_path / "in")


def test_file_that_fails_to_import(tmp_path):
    d = tmp_path / "in"
    d.mkdir()
    write_obj(d / "good.obj", CUBE_V, CUBE_F)
    (d / "broken.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 99\n\x00\x01")
    expect_refusal(["analyze", d, "--out", tmp_path / "o"], "broken.ply", inputs=d)


def test_mesh_without_faces_leaves_too_few_shapes(tmp_path):
    d = tmp_path / "in"
    d.mkdir()
    write_obj(d / "cube.obj", CUBE_V, CUBE_F)
    write_obj(d / "points.obj", CUBE_V)
    expect_refusal(["analyze", d, "--out", tmp_path / "o", "--renderer", "lineart"],
                   "points", "no faces", inputs=d)


def test_nan_coordinates_are_refused_naming_the_object(tmp_path):
    blend = tmp_path / "nan.blend"
    write_blend_with_bad_vertex(blend, "Broken", "float('nan')")
    before = blend.read_bytes()
    expect_refusal(["analyze", blend, "--out", tmp_path / "o", "--renderer", "lineart"], "Broken", "NaN")
    assert blend.read_bytes() == before


def test_unknown_names_in_labels_csv(sample, tmp_path):
    csv = tmp_path / "labels.csv"
    csv.write_text("name,style\nnot_a_shape,turned\nalso_missing,lattice\n")
    expect_refusal(["analyze", sample / "sample.blend", "--out", tmp_path / "o", "--labels", csv],
                   "not_a_shape", "also_missing")
    assert not (tmp_path / "o" / "result.blend").exists()


def test_bad_cluster_count(sample, tmp_path):
    expect_refusal(["analyze", sample / "sample.blend", "--out", tmp_path / "o", "--clusters", "one"],
                   "--clusters")


def test_folder_of_obj_files_gives_objects_with_results(sample, first_run, tmp_path):
    """A folder input: each file one shape named by its stem; result.blend holds them all."""
    out, _ = first_run
    before = digest(sample / "meshes")
    res = run_cmd("analyze", sample / "meshes", "--out", tmp_path, "--renderer", "lineart",
                  "--jobs", 2, "--cache", out.parent / "cache", "--rounds", 2)
    assert res.returncode == 0, res.stderr[-3000:]
    assert digest(sample / "meshes") == before
    state = blend_state(tmp_path / "result.blend")
    stems = {p.stem for p in (sample / "meshes").glob("*.obj")}
    assert set(state["objects"]) == stems
    assert all("style_weight" in o["groups"] for o in state["objects"].values())
    rep = json.loads((tmp_path / "report.json").read_text())
    assert {s["source"] for s in rep["shapes"]} == {str(p) for p in (sample / "meshes").glob("*.obj")}


def test_the_numpy_renderer_runs_the_whole_analysis(sample, tmp_path):
    """--renderer zbuffer (no render engine): every shape drawn, clustered and given regions."""
    res = run_cmd("analyze", sample / "sample.blend", "--out", tmp_path / "o", "--renderer",
                  "zbuffer", "--clusters", 2, "--cache", tmp_path / "cache")
    assert res.returncode == 0, res.stderr[-3000:]
    rep = json.loads((tmp_path / "o" / "report.json").read_text())
    assert rep["parameters"]["drawing"]["renderer"] == "zbuffer"
    assert len(rep["shapes"]) == len(blend_state(sample / "sample.blend")["objects"])
    assert {s["cluster"] for s in rep["shapes"]} == {0, 1}
    assert "automatic_k" not in rep and "next likeliest" not in res.stderr   # the user gave k
    assert "dictionary_agreement" in rep and "The clusters are" in res.stderr
    assert any(f.name.endswith(".npz") for f in (tmp_path / "cache").rglob("*"))
