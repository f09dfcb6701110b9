"""Write-back of a JobResult into a real scene: what appears, that re-runs replace rather than pile
up, that clearing gives the meshes back exactly, and that it all survives save and reload."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender



@pytest.fixture
def wb(ext):
    from style_coanalysis_ext.style_coanalysis.blender import writeback
    return writeback


@pytest.fixture
def job(ext):
    from style_coanalysis_ext.style_coanalysis.blender import job
    return job


def grid_object(name, n=6, offset=(0.0, 0.0, 0.0), mesh=None, collection=None):
    """An n x n quad grid (so faces are not triangles: write-back must handle polygons)."""
    if mesh is None:
        xs = np.linspace(-1, 1, n + 1)
        verts = [(x, y, 0.0) for y in xs for x in xs]
        faces = [(j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1,
                  (j + 1) * (n + 1) + i) for j in range(n) for i in range(n)]
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new(name, mesh)
    obj.location = offset
    (collection or bpy.context.scene.collection).objects.link(obj)
    return obj


def make_scene():
    """Props/A: two own materials used alternately; Props/B: no material; C and D share a mesh;
    E is never analysed."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    props = bpy.data.collections.new("Props")
    bpy.context.scene.collection.children.link(props)
    a = grid_object("A", collection=props)
    red, blue = bpy.data.materials.new("Red"), bpy.data.materials.new("Blue")
    a.data.materials.append(red)
    a.data.materials.append(blue)
    a.data.polygons.foreach_set("material_index", np.arange(len(a.data.polygons)) % 2)
    grid_object("B", collection=props)
    c = grid_object("C", offset=(3, 0, 0))
    grid_object("D", offset=(6, 0, 0), mesh=c.data)
    grid_object("E", offset=(9, 0, 0))


def weights_for(obj, side):
    """1 on one half of the grid (x > 0 or x < 0): a clear style region."""
    co = np.array([v.co[0] for v in obj.data.vertices])
    return ((co > 0) if side > 0 else (co < 0)).astype(np.float32)


def outcome(job, obj, cluster, weights, label=None, given=False):
    m = np.eye(4)
    m[:3, 3] = (0.0, -5.0, 1.0)
    return job.ShapeOutcome(
        name=obj.name, cluster=cluster, label=label, label_given=given, confidence=0.75,
        best_view=3, best_view_matrix=m.tolist(), vertex_weights=weights,
        style_vertex_fraction=float((weights > 0.5).mean()))


def result(job, names_clusters, side=1, labels=None):
    shapes = []
    for name, cluster in names_clusters:
        obj = bpy.data.objects[name]
        label = (labels or {}).get(name)
        shapes.append(outcome(job, obj, cluster, weights_for(obj, side), label, label is not None))
    ids = sorted({c for _, c in names_clusters})
    clusters = [{"id": c, "size": sum(1 for _, k in names_clusters if k == c),
                 "members": [n for n, k in names_clusters if k == c], "label": None} for c in ids]
    return job.JobResult(shapes=shapes, clusters=clusters, skipped=[], report={})


def snapshot():
    """Everything write-back may touch, to compare before / after clear."""
    out = {}
    for obj in bpy.context.scene.objects:
        me = obj.data
        idx = np.empty(len(me.polygons), np.int32)
        me.polygons.foreach_get("material_index", idx)
        out[obj.name] = dict(
            mats=[m.name if m else None for m in me.materials], idx=idx.tolist(),
            groups=[g.name for g in obj.vertex_groups], keys=sorted(obj.keys()),
            mesh_keys=sorted(me.keys()), attrs=sorted(a.name for a in me.attributes),
            cols=sorted(c.name for c in obj.users_collection))
    out["collections"] = sorted(c.name for c in bpy.data.collections)
    out["materials"] = sorted(m.name for m in bpy.data.materials)
    return out


ANALYSED = [("A", 0), ("B", 1), ("C", 1), ("D", 0)]


def test_write_marks_weights_material_properties_and_links(wb, job):
    make_scene()
    a = bpy.data.objects["A"]
    red, blue = a.data.materials[0], a.data.materials[1]
    original_idx = np.arange(len(a.data.polygons)) % 2
    summary = wb.write_results(bpy.context.scene, result(job, ANALYSED, labels={"A": "Baroque"}))

    # vertex group carries exactly the weights
    np.testing.assert_allclose(wb.vertex_weights(a), weights_for(a, 1))
    # own materials untouched and first; the highlight one is appended and shared
    hl = bpy.data.materials[wb.HIGHLIGHT]
    assert list(a.data.materials) == [red, blue, hl]
    b = bpy.data.objects["B"]
    assert list(b.data.materials) == [None, hl]      # padding keeps B's faces off the highlight
    assert sum(m.get(wb.MARK) == "highlight" for m in bpy.data.materials) == 1
    # faces with mean weight > 0.5 use the highlight slot, the others keep their own index
    idx = wb.material_indices(a.data)
    styled = wb.face_mean(a.data, weights_for(a, 1)) > 0.5
    assert 0 < styled.sum() < len(styled)
    assert np.all(idx[styled] == 2)
    assert np.array_equal(idx[~styled], original_idx[~styled])
    assert np.all(wb.material_indices(b.data)[~styled] == 0)
    # custom properties
    assert a["style_cluster"] == 0 and a["style_label"] == "Baroque" and a["style_label_given"]
    assert b["style_label"] == "" and not b["style_label_given"]
    assert a["style_confidence"] == pytest.approx(0.75) and a["style_best_view"] == 3
    assert list(a["style_best_view_matrix"])[3] == pytest.approx(0.0)
    assert list(a["style_best_view_matrix"])[7] == pytest.approx(-5.0)
    # collections link, never move
    parent = bpy.data.collections["Style Clusters"]
    assert parent.name in bpy.context.scene.collection.children
    assert sorted(c.name for c in parent.children) == ["Style Cluster 0", "Style Cluster 1"]
    assert {c.name for c in a.users_collection} == {"Props", "Style Cluster 0"}
    assert {c.name for c in b.users_collection} == {"Props", "Style Cluster 1"}
    assert "E" not in bpy.data.collections["Style Cluster 0"].objects
    assert "style_cluster" not in bpy.data.objects["E"]
    # scene-level results
    clusters = bpy.context.scene.style_coanalysis.clusters
    assert [(c.cluster_id, c.size) for c in clusters] == [(0, 2), (1, 2)]
    assert summary["shared_meshes"] == [bpy.data.objects["C"].data.name]


def test_shared_mesh_written_once_with_mean_weights(wb, job):
    make_scene()
    c, d = bpy.data.objects["C"], bpy.data.objects["D"]
    res = result(job, ANALYSED)
    for s in res.shapes:
        if s.name == "D":
            s.vertex_weights = np.zeros_like(s.vertex_weights)
    wb.write_results(bpy.context.scene, res)
    assert len(c.data.materials) == 2 and c.data.materials[1].name == wb.HIGHLIGHT
    assert [g.name for g in c.vertex_groups] == [wb.GROUP]
    np.testing.assert_allclose(wb.vertex_weights(d), 0.5 * weights_for(c, 1))
    assert c["style_cluster"] == 1 and d["style_cluster"] == 0


def test_rerun_replaces_and_clear_restores_exactly(wb, job):
    make_scene()
    before = snapshot()
    scene = bpy.context.scene
    wb.write_results(scene, result(job, ANALYSED))
    once = snapshot()
    # a second run with other clusters and other weights replaces, never duplicates
    wb.write_results(scene, result(job, [("A", 1), ("B", 1), ("C", 2), ("D", 2)], side=-1))
    twice = snapshot()
    for name in "ABCD":
        assert twice[name]["mats"] == once[name]["mats"]
        assert twice[name]["groups"] == [wb.GROUP]
    assert sorted(twice["materials"]) == sorted(once["materials"])
    assert sorted(c.name for c in bpy.data.collections["Style Clusters"].children) == \
        ["Style Cluster 1", "Style Cluster 2"]
    assert "Style Cluster 0" not in bpy.data.collections
    a = bpy.data.objects["A"]
    np.testing.assert_allclose(wb.vertex_weights(a), weights_for(a, -1))
    assert a["style_cluster"] == 1
    # clear: the scene is as before the first run, to the material index
    wb.clear_results(scene)
    assert snapshot() == before
    assert len(scene.style_coanalysis.clusters) == 0


def test_refuses_before_changing_anything(wb, job):
    make_scene()
    before = snapshot()
    res = result(job, ANALYSED)
    res.shapes[1].vertex_weights = res.shapes[1].vertex_weights[:-1]    # B: one weight short
    res.shapes.append(outcome(job, bpy.data.objects["E"], 0, np.zeros(3, np.float32)))
    res.shapes[-1].name = "Gone"
    with pytest.raises(wb.WritebackError) as err:
        wb.write_results(bpy.context.scene, res)
    assert "'B'" in str(err.value) and "'Gone'" in str(err.value)
    assert snapshot() == before


def test_highlight_toggle_is_exact(wb, job):
    make_scene()
    a = bpy.data.objects["A"]
    wb.write_results(bpy.context.scene, result(job, ANALYSED))
    shown = wb.material_indices(a.data).copy()
    assert wb.set_highlight_shown(a, False)
    assert np.array_equal(wb.material_indices(a.data), np.arange(len(a.data.polygons)) % 2)
    assert wb.set_highlight_shown(a, True)
    assert np.array_equal(wb.material_indices(a.data), shown)


def test_results_survive_save_and_reload(wb, job, tmp_path):
    make_scene()
    before = snapshot()
    wb.write_results(bpy.context.scene, result(job, ANALYSED, labels={"B": "Ming"}))
    written = snapshot()
    path = str(tmp_path / "results.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert "A" not in bpy.data.objects
    bpy.ops.wm.open_mainfile(filepath=path)
    assert snapshot() == written
    a, b = bpy.data.objects["A"], bpy.data.objects["B"]
    np.testing.assert_allclose(wb.vertex_weights(a), weights_for(a, 1))
    assert b["style_label"] == "Ming" and b["style_label_given"]
    assert [(c.cluster_id, c.size) for c in bpy.context.scene.style_coanalysis.clusters] == \
        [(0, 2), (1, 2)]
    # the stored original indices still make clear exact after a reload
    wb.clear_results(bpy.context.scene)
    assert snapshot() == before
