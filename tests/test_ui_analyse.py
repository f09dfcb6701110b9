"""The Analyse operator and the results operators, with the job's generator replaced by a quick
stand-in (the real analysis is exercised by the job's own tests): what the operator hands to the
job, that it writes back once at the end, and that a failed run leaves the scene as it was."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender



NAMES = ("Chair_a", "Chair_b", "Table_a", "Table_b")


@pytest.fixture
def scene(ext):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    for k, name in enumerate(NAMES):
        bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=2, location=(3 * k, 0, 0))
        bpy.context.object.name = name
        bpy.context.object.data.name = name
    for o in bpy.context.scene.objects:
        o.select_set(True)
    return bpy.context.scene


class FakeJob:
    """Stands in for job.run_steps: records what it was given; clusters by name prefix; style
    weight 1 on the upper half of each shape; optionally fails after a few steps."""

    def __init__(self, job, fail=False):
        self.job, self.fail, self.calls = job, fail, []

    def __call__(self, meshes, options):
        self.calls.append((meshes, options))
        for i in range(len(meshes)):
            yield ("render", i, len(meshes))
            if self.fail and i == 1:
                from style_coanalysis_ext.style_coanalysis.meshes import InputError
                raise InputError(f"'{meshes[1].name}' could not be drawn")
        shapes = []
        for m in meshes:
            cam = np.eye(4)
            cam[:3, 3] = m.vertices.mean(0) + np.array([0.0, -4.0, 1.0])
            w = (m.vertices[:, 2] > m.vertices[:, 2].mean()).astype(np.float32)
            cluster = 0 if m.name.startswith("Chair") else 1
            label = (options.labels or {}).get(m.name) or ("Ming" if cluster == 0 else "Qing")
            shapes.append(self.job.ShapeOutcome(
                name=m.name, cluster=cluster, label=label,
                label_given=m.name in (options.labels or {}), confidence=0.9, best_view=5,
                best_view_matrix=cam.tolist(), vertex_weights=w,
                style_vertex_fraction=float(w.mean())))
        clusters = [{"id": c, "size": sum(s.cluster == c for s in shapes),
                     "members": [s.name for s in shapes if s.cluster == c],
                     "label": ("Ming", "Qing")[c]} for c in (0, 1)]
        yield ("done", len(meshes), len(meshes))
        return self.job.JobResult(shapes=shapes, clusters=clusters, skipped=[], report={})


@pytest.fixture
def job(ext):
    from style_coanalysis_ext.style_coanalysis.blender import job
    return job


@pytest.fixture
def fake(job, monkeypatch):
    f = FakeJob(job)
    monkeypatch.setattr(job, "run_steps", f)
    return f


def test_analyse_hands_constraints_and_settings_to_the_job(scene, fake):
    s = scene.style_coanalysis
    bpy.ops.style.label_add(name="Ming")
    bpy.ops.style.label_add(name="Qing")
    bpy.data.objects["Chair_a"].style_coanalysis.label = "Ming"
    bpy.data.objects["Table_b"].style_coanalysis.label = "Qing"
    bpy.data.objects["Table_a"].style_coanalysis.label = "Gone"       # not a label any more
    s.auto_clusters, s.n_clusters, s.eta, s.max_rounds, s.renderer = False, 2, 0.3, 2, "lineart"
    s.method = "paper"
    assert bpy.ops.style.analyse() == {"FINISHED"}
    (meshes, options), = fake.calls
    assert [m.name for m in meshes] == list(NAMES)
    assert options.labels == {"Chair_a": "Ming", "Table_b": "Qing"} and options.triplets is None
    assert options.renderer == "lineart" and options.params.method == "paper"
    assert options.params.n_clusters == 2 and options.params.eta == pytest.approx(0.3)
    assert options.params.max_rounds == 2 and options.params.n_representatives == 50
    # written back once, at the end
    assert [(c.cluster_id, c.size, c.label) for c in s.clusters] == [(0, 2, "Ming"), (1, 2, "Qing")]
    chair = bpy.data.objects["Chair_a"]
    assert chair["style_cluster"] == 0 and chair["style_label_given"]
    assert chair.vertex_groups.get("style_weight") is not None
    # triplets instead of labels
    bpy.data.objects["Chair_a"].style_coanalysis.label = ""
    bpy.data.objects["Table_b"].style_coanalysis.label = ""
    bpy.ops.style.triplet_add(a="Chair_a", b="Chair_b", c="Table_a")
    assert bpy.ops.style.analyse() == {"FINISHED"}
    options = fake.calls[-1][1]
    assert options.triplets == [("Chair_a", "Chair_b", "Table_a")] and options.labels is None
    # back to the default method: PSLF's parameters (greyed out) are not handed over, so the
    # value left from the paper's run neither stops the run nor reaches the analysis
    s.method = "default"
    assert bpy.ops.style.analyse() == {"FINISHED"}
    options = fake.calls[-1][1]
    assert options.params.method == "default" and options.params.eta == pytest.approx(0.2)
    assert options.params.max_rounds == 2


def test_operator_defaults_come_from_params(ext, scene):
    """One source of truth: the panel's defaults are AnalysisParams' (issue 12)."""
    from style_coanalysis_ext.style_coanalysis.params import AnalysisParams
    from style_coanalysis_ext.style_coanalysis.blender.properties import PARAMETER_PROPS
    from style_coanalysis_ext.style_coanalysis.options import PARAMETERS
    p, s = AnalysisParams(), scene.style_coanalysis
    for option, prop in PARAMETER_PROPS.items():
        assert getattr(s, prop) == pytest.approx(getattr(p, PARAMETERS[option][0])), prop
    assert s.method == p.method == "default"


def test_bad_settings_are_refused_before_the_job_starts(scene, fake):
    """Labels and triplets together, labels of one style, a cluster count the labels do not
    make, or more clusters than shapes: refused up front by the same checks as the command
    line, and the job never starts (issue 12, item 4)."""
    s = scene.style_coanalysis
    bpy.ops.style.label_add(name="Ming")
    bpy.data.objects["Chair_a"].style_coanalysis.label = "Ming"
    bpy.ops.style.triplet_add(a="Chair_a", b="Chair_b", c="Table_a")
    with pytest.raises(RuntimeError, match="labels or triplets, not both"):
        bpy.ops.style.analyse()
    bpy.ops.style.triplet_remove()
    with pytest.raises(RuntimeError, match="at least two different styles, found only 'Ming'"):
        bpy.ops.style.analyse()                  # the pipeline would find it only after drawing
    bpy.ops.style.label_add(name="Qing")
    bpy.data.objects["Table_a"].style_coanalysis.label = "Qing"
    s.auto_clusters, s.n_clusters = False, 3
    with pytest.raises(RuntimeError, match="--clusters 3 with labels of 2 styles"):
        bpy.ops.style.analyse()
    bpy.data.objects["Chair_a"].style_coanalysis.label = ""
    bpy.data.objects["Table_a"].style_coanalysis.label = ""
    s.n_clusters = 5
    with pytest.raises(RuntimeError, match="more clusters than the 4"):
        bpy.ops.style.analyse()
    assert fake.calls == []


def test_failed_run_leaves_the_scene_as_it_was(scene, job, monkeypatch):
    monkeypatch.setattr(job, "run_steps", FakeJob(job, fail=True))
    keys = {o.name: sorted(o.keys()) for o in scene.objects}
    mats = len(bpy.data.materials)
    with pytest.raises(RuntimeError, match="'Chair_b' could not be drawn"):
        bpy.ops.style.analyse()
    assert {o.name: sorted(o.keys()) for o in scene.objects} == keys
    assert len(bpy.data.materials) == mats and "Style Clusters" not in bpy.data.collections
    assert all(len(o.vertex_groups) == 0 for o in scene.objects)


def test_modifier_changing_vertex_count_is_skipped_by_name(scene, fake, capfd):
    bpy.data.objects["Table_b"].modifiers.new("Sub", "SUBSURF")
    capfd.readouterr()
    assert bpy.ops.style.analyse() == {"FINISHED"}
    said = capfd.readouterr()
    assert "'Table_b' skipped: its modifiers change the vertex count" in said.out + said.err
    (meshes, _), = fake.calls
    assert "Table_b" not in [m.name for m in meshes]
    assert "style_cluster" not in bpy.data.objects["Table_b"]


def test_collection_target(scene, fake):
    col = bpy.data.collections.new("Chairs")
    scene.collection.children.link(col)
    for n in ("Chair_a", "Chair_b"):
        col.objects.link(bpy.data.objects[n])
    s = scene.style_coanalysis
    s.target = "COLLECTION"
    assert not bpy.ops.style.analyse.poll()              # no collection chosen yet
    s.target_collection = col
    assert bpy.ops.style.analyse() == {"FINISHED"}
    assert [m.name for m in fake.calls[0][0]] == ["Chair_a", "Chair_b"]


def test_results_operators(scene, fake):
    assert bpy.ops.style.analyse() == {"FINISHED"}
    s = scene.style_coanalysis
    # select a cluster's members
    assert bpy.ops.style.select_cluster(cluster=1) == {"FINISHED"}
    assert sorted(o.name for o in bpy.context.selected_objects) == ["Table_a", "Table_b"]
    # accept the prediction of the active object as its own label (creating the label)
    bpy.context.view_layer.objects.active = bpy.data.objects["Table_a"]
    assert bpy.ops.style.accept_prediction() == {"FINISHED"}
    assert bpy.data.objects["Table_a"].style_coanalysis.label == "Qing"
    assert "Qing" in s.label_names()
    assert not bpy.ops.style.accept_prediction.poll()   # already accepted
    # camera to the best view
    assert bpy.ops.style.best_view_camera() == {"FINISHED"}
    cam = bpy.data.objects["Style Best View"]
    assert scene.camera == cam
    expected = np.array(bpy.data.objects["Table_a"]["style_best_view_matrix"]).reshape(4, 4)
    np.testing.assert_allclose(np.array(cam.matrix_world), expected, atol=1e-5)
    assert bpy.ops.style.best_view_camera() == {"FINISHED"}      # reused, not duplicated
    assert sum(o.type == "CAMERA" for o in bpy.data.objects) == 1
    # hide and show the highlight
    table = bpy.data.objects["Table_a"]
    hl = len(table.data.materials) - 1
    shown = sum(p.material_index == hl for p in table.data.polygons)
    assert shown > 0
    assert bpy.ops.style.toggle_highlight() == {"FINISHED"}
    assert sum(p.material_index == hl for p in table.data.polygons) == 0
    assert bpy.ops.style.toggle_highlight() == {"FINISHED"}
    assert sum(p.material_index == hl for p in table.data.polygons) == shown
    # clear everything the run wrote
    assert bpy.ops.style.clear_results() == {"FINISHED"}
    assert len(s.clusters) == 0 and "style_cluster" not in table
    assert len(table.data.materials) == 0
    assert not bpy.ops.style.clear_results.poll()


def test_panels_and_lists_are_registered(ext):
    for name in ("VIEW3D_PT_style", "VIEW3D_PT_style_advanced", "VIEW3D_PT_style_labels",
                 "VIEW3D_PT_style_triplets", "VIEW3D_PT_style_results", "VIEW3D_PT_style_decimate",
                 "OBJECT_PT_style_results", "STYLE_UL_labels", "STYLE_UL_triplets",
                 "STYLE_UL_clusters"):
        assert hasattr(bpy.types, name), name
    assert bpy.types.VIEW3D_PT_style.bl_category == "Style"


def test_stepper_progress_result_and_cancel(ext):
    """The modal path's logic, without a window: budgeted steps, the result, and Esc closing the
    generator so the job's clean-up runs (and nothing is returned to write back)."""
    from style_coanalysis_ext.operators.analyse import Stepper
    log = []

    def job():
        try:
            for i in range(5):
                log.append(i)
                yield ("render", i, 5)
            return "result"
        finally:
            log.append("closed")

    ticks = iter(range(100))
    st = Stepper(job(), budget_s=2, clock=lambda: next(ticks))   # two steps per advance
    assert st.advance() and st.progress == ("render", 1, 5) and log == [0, 1]
    assert st.fraction() == pytest.approx(0.2) and "render 1/5" in st.status()
    st.cancel()
    assert log[-1] == "closed" and st.result is None
    assert Stepper(job()).run_to_end() == "result"


class CheckingLayout:
    """Stands in for UILayout (panels cannot draw in background mode) and checks what a panel
    asks for: every property exists on its data, every operator exists and every operator
    property set by the panel is one of its own."""

    def __init__(self, seen):
        self.seen = seen

    def __getattr__(self, name):            # enabled, use_property_split, ... are plain flags
        return None

    def _child(self, *a, **k):
        return CheckingLayout(self.seen)

    row = column = box = split = _child

    def label(self, **k):
        self.seen.append(("label", k.get("text")))

    def prop(self, data, name, **k):
        assert name in data.bl_rna.properties, f"{data} has no property {name!r}"
        self.seen.append(("prop", name))

    def template_list(self, list_id, _list, data, coll, active_data, active, **k):
        assert hasattr(bpy.types, list_id), list_id
        assert coll in data.bl_rna.properties and active in active_data.bl_rna.properties
        self.seen.append(("list", list_id))

    def operator(self, idname, **k):
        cat, name = idname.split(".")
        op = getattr(getattr(bpy.ops, cat), name)
        names = set(op.get_rna_type().properties.keys())
        self.seen.append(("op", idname))

        class Props:
            def __setattr__(self, key, value):
                assert key in names, f"{idname} has no property {key!r}"

        return Props()


def test_panels_draw_what_exists(scene, fake):
    """Every panel's draw, before and after a run, only uses existing properties and operators."""
    from types import SimpleNamespace
    from style_coanalysis_ext import panels
    ctx = bpy.context
    for when in ("before", "after"):
        if when == "after":
            assert bpy.ops.style.analyse() == {"FINISHED"}
            bpy.ops.style.decimate(ratio=0.5)
        seen = []
        for cls in panels.CLASSES:
            if issubclass(cls, bpy.types.Panel):
                fake_self = SimpleNamespace(layout=CheckingLayout(seen))
                cls.draw(fake_self, SimpleNamespace(scene=ctx.scene, object=ctx.active_object,
                                                    active_object=ctx.active_object,
                                                    selected_objects=ctx.selected_objects))
        ops = {v for k, v in seen if k == "op"}
        assert {"style.analyse", "style.label_add", "style.triplet_add", "style.decimate",
                "style.best_view_camera", "style.clear_results"} <= ops
    # after the run the active object's results are shown
    assert any(k == "label" and v and v.startswith("Cluster ") for k, v in seen)
