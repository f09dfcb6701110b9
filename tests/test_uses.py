"""The uses of an analysis end to end (issue 14): `analyze` writes the style space, `similar` and
`suggest-labels` read it headless, and the Style panel's buttons run as real operators on the
saved result.blend. Real parts only: sample shapes, Line Art drawings, the real analysis."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from style_coanalysis.constraints import read_labels_csv
from style_coanalysis.meshes import InputError
from style_coanalysis.options import check_output
from style_coanalysis.similarity import SPACE_FILE, StyleSpace
from style_coanalysis.suggest import suggest

bpy = pytest.importorskip("bpy")
ROOT = Path(__file__).resolve().parent.parent
pytestmark = [pytest.mark.blender, pytest.mark.slow]


def run_cmd(*args, timeout=900):
    return subprocess.run([sys.executable, "-m", "style_coanalysis", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    """A 12-shape sample in base/sample; base/cache its drawings."""
    base = tmp_path_factory.mktemp("uses")
    res = run_cmd("sample", "--out", base / "sample", "--size", 12, "--seed", 5)
    assert res.returncode == 0, res.stderr[-3000:]
    return base


@pytest.fixture(scope="module")
def result(base):
    """The sample analysed: (result folder, its style space)."""
    out = base / "result"
    res = run_cmd("analyze", base / "sample" / "sample.blend", "--out", out, "--renderer",
                  "lineart", "--jobs", 2, "--cache", base / "cache", "--rounds", 2)
    assert res.returncode == 0, res.stderr[-3000:]
    return out, StyleSpace.load(out)


def test_analyze_writes_the_style_space(result):
    import json
    out, space = result
    shapes = [s["name"] for s in json.loads((out / "report.json").read_text())["shapes"]]
    assert sorted(space.names) == sorted(shapes)
    assert space.features.shape[0] == len(shapes)
    check_output(out)       # a result with its style space may be replaced by the next run


def test_similar_prints_the_ranking(result):
    out, space = result
    name = space.names[3]
    res = run_cmd("similar", out, name, "--top", 4)
    assert res.returncode == 0, res.stderr
    rows = [line.split(",") for line in res.stdout.splitlines()[2:]]
    assert [r[1] for r in rows] == [n for n, _ in space.ranking(name, 4)]
    dist = [float(r[2]) for r in rows]
    assert dist == sorted(dist) and name not in [r[1] for r in rows]


def test_similar_scores_triplets(result, tmp_path):
    out, space = result
    a, others = space.names[0], [n for n, _ in space.ranking(space.names[0])]
    csv = tmp_path / "held_out.csv"
    csv.write_text(f"a,b,c\n{a},{others[0]},{others[-1]}\n{a},{others[-1]},{others[1]}\n")
    res = run_cmd("similar", out, "--triplets", csv)
    assert res.returncode == 0, res.stderr
    assert "triplet accuracy 0.500 (1 of 2 triplets" in res.stdout


def test_similar_refuses_bad_input(result, tmp_path):
    out, _ = result
    res = run_cmd("similar", out, "Nope")
    assert res.returncode == 2 and "'Nope' is not among the analysed shapes" in res.stderr
    assert res.stdout == ""
    res = run_cmd("similar", tmp_path, "x")
    assert res.returncode == 2 and f"holds no {SPACE_FILE}" in res.stderr
    res = run_cmd("similar", out)
    assert res.returncode == 2 and "give a shape NAME" in res.stderr


def test_suggest_labels_writes_a_labels_csv(result, tmp_path):
    out, space = result
    target = tmp_path / "next.csv"
    res = run_cmd("suggest-labels", out, "--n", 3, "--out", target)
    assert res.returncode == 0, res.stderr
    rows = [l for l in target.read_text().splitlines() if l and not l.startswith("#")]
    assert rows[0] == "name,style"
    names = [r.rstrip(",") for r in rows[1:]]
    assert names == [p.name for p in suggest(space, 3)]
    with pytest.raises(InputError, match="expected 'name,style'"):   # styles still to fill in
        read_labels_csv(target, space.names)
    filled = target.read_text().replace(f"{names[0]},", f"{names[0]},A") \
        .replace(f"{names[1]},", f"{names[1]},B").replace(f"{names[2]},", f"{names[2]},A")
    target.write_text(filled)
    assert read_labels_csv(target, space.names) == {names[0]: "A", names[1]: "B", names[2]: "A"}


def test_suggest_labels_refuses_to_write_into_the_result(result):
    out, _ = result
    before = sorted(p.name for p in out.iterdir())
    res = run_cmd("suggest-labels", out, "--out", out / "next.csv")
    assert res.returncode == 2 and "inside the result folder" in res.stderr
    assert sorted(p.name for p in out.iterdir()) == before
    res = run_cmd("suggest-labels", out, "--n", 0)
    assert res.returncode == 2 and "--n must be at least 1" in res.stderr


def selected():
    return {o.name for o in bpy.context.view_layer.objects if o.select_get()}


def test_buttons_on_the_saved_result(result, ext, tmp_path):
    out, space = result
    bpy.ops.wm.open_mainfile(filepath=str(out / "result.blend"))
    scene = bpy.context.scene
    name = space.names[2]
    bpy.context.view_layer.objects.active = bpy.data.objects[name]
    assert bpy.ops.style.select_similar(count=3) == {"FINISHED"}
    want = [n for n, _ in space.ranking(name, 3)]
    assert selected() == {name, *want}
    assert bpy.context.view_layer.objects.active.name == name
    from style_coanalysis_ext.operators.uses import SIMILAR_KEY, SUGGESTED_KEY, read_list
    assert [r[0] for r in read_list(scene, SIMILAR_KEY)["ranked"]] == want

    # suggestions skip shapes labelled since the analysis (Labels panel)
    picks = [p.name for p in suggest(space, 2)]
    assert bpy.ops.style.suggest_labels(count=2) == {"FINISHED"}
    assert selected() == set(picks)
    assert [n for n, _ in read_list(scene, SUGGESTED_KEY)] == picks
    bpy.data.objects[picks[0]].style_coanalysis.label = "Mine"
    assert bpy.ops.style.suggest_labels(count=2) == {"FINISHED"}
    assert picks[0] not in selected() and len(selected()) == 2

    # an object the analysis never saw: the button says why it cannot run
    mesh = bpy.data.meshes.new("New")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
    obj = bpy.data.objects.new("New", mesh)
    scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    assert not bpy.ops.style.select_similar.poll()
    with pytest.raises(RuntimeError, match="'New' was not in the last style analysis"):
        bpy.ops.style.select_similar()

    # the space survives save and reload; Clear Style Results switches both buttons off
    path = str(tmp_path / "saved.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    bpy.context.view_layer.objects.active = bpy.data.objects[name]
    assert bpy.ops.style.select_similar(count=3) == {"FINISHED"}
    assert selected() == {name, *want}
    assert bpy.ops.style.clear_results() == {"FINISHED"}
    assert not bpy.ops.style.select_similar.poll()
    assert not bpy.ops.style.suggest_labels.poll()


def synthetic_drawings(folder, invert_second=True):
    """Two 'styles' of plain line drawings: curvy (circles) and straight (boxes), 3 each, of
    different sizes; the straight ones light on dark."""
    from PIL import Image
    from skimage.draw import circle_perimeter, rectangle_perimeter
    for k in range(3):
        size = 150 + 50 * k
        for style in ("curvy", "straight"):
            img = np.zeros((size, size), np.uint8)
            if style == "curvy":
                for r in (size // 3, size // 5, size // 9):
                    rr, cc = circle_perimeter(size // 2, size // 2, r, shape=img.shape)
                    img[rr, cc] = 255
            else:
                for d in (size // 8, size // 4, size // 3):
                    rr, cc = rectangle_perimeter((d, d), (size - d, size - d), shape=img.shape)
                    img[rr, cc] = 255
            (folder / style).mkdir(parents=True, exist_ok=True)
            out = img if (style == "straight" and invert_second) else 255 - img
            Image.fromarray(out).save(folder / style / f"{k}.png")
    return folder


def test_identify_command(base, tmp_path):
    import csv
    drawings = synthetic_drawings(tmp_path / "drawings")
    out = tmp_path / "identified"
    res = run_cmd("identify", base / "sample" / "sample.blend", "--drawings", drawings, "--out",
                  out, "--renderer", "lineart", "--jobs", 2, "--cache", base / "cache")
    assert res.returncode == 0, res.stderr[-3000:]
    rows = list(csv.DictReader((out / "identify.csv").open()))
    assert len(rows) == 12
    for r in rows:
        assert r["style"] in ("curvy", "straight")
        votes = {"curvy": int(r["votes_curvy"]), "straight": int(r["votes_straight"])}
        assert sum(votes.values()) == 12 and votes[r["style"]] == max(votes.values())
    check_region_files(out, base / "sample" / "sample.blend")


def check_region_files(out, blend):
    """identify.json's region weights: per shape one weight per vertex and per triangle of its
    mesh, the vertex weights those of the faces around them (the style regions lie on faces),
    and the shape's summary counting the same faces; the folder may be replaced by the next run.
    Returns (meshes, face weights, json)."""
    import json

    from style_coanalysis import regions
    from style_coanalysis.blender.scene import meshes_from_blend
    from style_coanalysis.meshes import face_areas, normalise
    check_output(out)
    info = json.loads((out / "identify.json").read_text())
    by_name = {m.name: m for m in meshes_from_blend(blend)}
    meshes, faces_w = [], []
    assert len(info["region_weights"]) == len(info["shapes"])
    for shape, weights in zip(info["shapes"], info["region_weights"]):
        m = by_name[shape["name"]]
        assert weights["name"] == shape["name"]
        vw, fw = np.array(weights["vertex"]), np.array(weights["face"])
        assert vw.shape == (len(m.vertices),) and fw.shape == (len(m.faces),)
        assert vw.min() >= 0 and vw.max() <= 1 and fw.min() >= 0 and fw.max() <= 1
        areas = face_areas(normalise(m).vertices, m.faces)
        # weights are written to 4 decimals
        assert np.allclose(vw, regions.vertex_weights(fw, m.faces, areas, len(m.vertices)), atol=2e-4)
        assert shape["region"]["faces"] == int((fw > 0.5).sum())
        meshes.append(m)
        faces_w.append(fw)
    assert sorted(info["characteristic_words"]) == sorted({s["style"] for s in info["drawings"]})
    return meshes, faces_w, info


@pytest.fixture(scope="module")
def sketches(base):
    """Stand-in sketches (evaluation.sketches) of 8 sample meshes the test set does not hold
    (another generator seed), 2 per style, 5 unseen views each, in one subfolder per style."""
    from style_coanalysis.blender.batch import draw_collection
    from style_coanalysis.evaluation.sketches import SKETCH_SETTINGS, write_sketches
    from style_coanalysis.sample import generate
    meshes = []
    for m in generate(size=24, seed=1):
        if sum(n.truth["style"] == m.truth["style"] for n in meshes) < 2:
            meshes.append(m)
    for m in meshes:
        m.name = "sketch_" + m.name
    drawn, bad = draw_collection(meshes, SKETCH_SETTINGS, None, jobs=2)
    assert not bad
    styles = {m.name: m.truth["style"] for m in meshes}
    folder = base / "sketches"
    write_sketches(drawn, [styles[d.name] for d in drawn], folder, seed=0)
    return folder


def test_identify_marks_style_regions_from_sketches(base, sketches, tmp_path):
    """With sketches of the sample's own styles, the identified styles' regions are found on
    the surface: most shapes get a region, and over all shapes the region faces are more often
    decorative (by area, the generator's per-face truth) than the surface as a whole, which is
    what faces drawn at random would reach. The bench measures it on 120 shapes."""
    out = tmp_path / "identified"
    res = run_cmd("identify", base / "sample" / "sample.blend", "--drawings", sketches, "--out",
                  out, "--renderer", "lineart", "--jobs", 2, "--cache", base / "cache")
    assert res.returncode == 0, res.stderr[-3000:]
    from style_coanalysis.meshes import face_areas, normalise
    meshes, faces_w, info = check_region_files(out, base / "sample" / "sample.blend")
    styles = {m.truth["style"] for m in meshes}
    assert {s["style"] for s in info["shapes"]} <= styles
    assert all(info["characteristic_words"][s] for s in styles)   # each style has its words
    with_region = [fw.max() > 0.5 for fw in faces_w]
    assert sum(with_region) >= len(meshes) / 2, [s["region"] for s in info["shapes"]]
    inside = decorative = total_decorative = total = 0.0
    for m, fw in zip(meshes, faces_w):
        area = face_areas(normalise(m).vertices, m.faces)
        truth = np.asarray(m.truth["face_mask"], bool)
        inside += area[fw > 0.5].sum()
        decorative += area[(fw > 0.5) & truth].sum()
        total += area.sum()
        total_decorative += area[truth].sum()
    assert decorative / inside > total_decorative / total


def test_identify_refuses_a_bad_drawing_before_rendering(base, tmp_path):
    drawings = synthetic_drawings(tmp_path / "drawings")
    (drawings / "curvy" / "broken.png").write_bytes(b"not a png")
    out = tmp_path / "identified"
    res = run_cmd("identify", base / "sample" / "sample.blend", "--drawings", drawings, "--out",
                  out, "--renderer", "lineart", "--cache", tmp_path / "cache")
    assert res.returncode == 2 and "broken.png' is not a readable image" in res.stderr
    assert not out.exists() and not (tmp_path / "cache").exists()    # nothing drawn or written


def test_identify_button(base, ext, tmp_path):
    import json
    drawings = synthetic_drawings(tmp_path / "drawings")
    bpy.ops.wm.open_mainfile(filepath=str(base / "sample" / "sample.blend"))
    scene = bpy.context.scene
    scene.style_coanalysis.renderer = "lineart"
    scene.style_coanalysis.max_rounds = 2
    meshes = [o for o in scene.objects if o.type == "MESH"]
    for o in scene.objects:
        o.select_set(o.type == "MESH")

    def state():
        """What else of the scene the button could touch."""
        return ({o.name: (sorted(g.name for g in o.vertex_groups), sorted(o.keys()))
                 for o in bpy.data.objects}, sorted(bpy.data.collections.keys()),
                sorted(bpy.data.materials.keys()), sorted(bpy.data.meshes.keys()))
    before = state()

    (drawings / "curvy" / "broken.jpg").write_bytes(b"no jpeg")
    with pytest.raises(RuntimeError, match="broken.jpg' is not a readable image"):
        bpy.ops.style.identify_from_drawings(directory=str(drawings))
    assert state() == before                                          # nothing written
    (drawings / "curvy" / "broken.jpg").unlink()

    # a result that does not fit one object (its mesh changed): refused before any write
    from types import SimpleNamespace

    from style_coanalysis.identify import Identification
    from style_coanalysis_ext.operators.uses import IDENTIFIED_GROUP, write_identified
    from style_coanalysis_ext.style_coanalysis.blender.writeback import WritebackError
    sizes = [len(o.data.vertices) for o in meshes]
    sizes[-1] += 1
    bad = SimpleNamespace(job=SimpleNamespace(shapes=[SimpleNamespace(name=o.name) for o in meshes]),
                          regions=[SimpleNamespace(weights=np.ones(n, np.float32)) for n in sizes],
                          found=[Identification("curvy", {"curvy": 12}, [])] * len(meshes))
    with pytest.raises(WritebackError, match=f"'{meshes[-1].name}' has"):
        write_identified(scene, bad)
    assert state() == before

    assert bpy.ops.style.identify_from_drawings(directory=str(drawings)) == {"FINISHED"}
    from style_coanalysis_ext.style_coanalysis.blender.writeback import vertex_weights
    for o in meshes:
        votes = json.loads(o["style_identified_votes"])
        assert o["style_identified"] in ("curvy", "straight")
        assert sum(votes.values()) == 12 and votes[o["style_identified"]] == max(votes.values())
        w = vertex_weights(o, group=IDENTIFIED_GROUP)
        assert o.vertex_groups.get(IDENTIFIED_GROUP) is not None
        assert w.shape == (len(o.data.vertices),) and w.min() >= 0 and w.max() <= 1
    objects, *rest = state()
    assert rest == list(before[1:])                 # no collection, material or mesh added
    for name, (groups, keys) in objects.items():    # only the group and properties added
        added = ({IDENTIFIED_GROUP}, {"style_identified", "style_identified_votes"}) \
            if name in {o.name for o in meshes} else (set(), set())
        assert set(groups) == set(before[0][name][0]) | added[0]
        assert set(keys) == set(before[0][name][1]) | added[1]
    from style_coanalysis_ext.operators.uses import IDENTIFIED_KEY, read_list
    assert sorted(r[0] for r in read_list(scene, IDENTIFIED_KEY)) == sorted(o.name for o in meshes)
    # Clear Style Results takes the identification away too, and leaves the scene as before it
    assert bpy.ops.style.clear_results() == {"FINISHED"}
    assert state() == before and IDENTIFIED_KEY not in scene
