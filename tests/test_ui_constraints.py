"""Label and triplet operators, run as a person would (bpy.ops with the extension registered):
they must change the stored constraints exactly as intended, explain when they are unavailable,
and the constraints must survive save and reload."""

import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender



@pytest.fixture
def scene(ext):
    """Four meshes Chair, Table, Stool, Bed and a camera, nothing selected."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    for name in ("Chair", "Table", "Stool", "Bed"):
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
        bpy.context.scene.collection.objects.link(bpy.data.objects.new(name, mesh))
    cam = bpy.data.objects.new("Cam", bpy.data.cameras.new("Cam"))
    bpy.context.scene.collection.objects.link(cam)
    return bpy.context.scene


def select(*names, active=None):
    for o in bpy.context.scene.objects:
        o.select_set(o.name in names)
    bpy.context.view_layer.objects.active = bpy.data.objects[active] if active else None


def labels_of(scene):
    return [(lab.name, tuple(round(c, 3) for c in lab.color)) for lab in
            scene.style_coanalysis.labels]


def assigned():
    return {o.name: o.style_coanalysis.label for o in bpy.data.objects
            if o.type == "MESH" and o.style_coanalysis.label}


def triplets_of(scene):
    return [t.names() for t in scene.style_coanalysis.triplets]


def test_labels_add_rename_colour_assign_clear_remove(scene):
    s = scene.style_coanalysis
    assert not bpy.ops.style.label_assign.poll()        # no labels yet
    assert bpy.ops.style.label_add() == {"FINISHED"}
    assert bpy.ops.style.label_add(name="Ming") == {"FINISHED"}
    assert [n for n, _ in labels_of(scene)] == ["Style 1", "Ming"]
    assert s.active_label_index == 1

    select("Chair", "Stool", "Cam", active="Chair")
    assert bpy.ops.style.label_assign() == {"FINISHED"}     # active label: Ming; the camera is no mesh
    select("Table")
    assert bpy.ops.style.label_assign(index=0) == {"FINISHED"}
    assert assigned() == {"Chair": "Ming", "Stool": "Ming", "Table": "Style 1"}

    # renaming follows onto the objects; a taken name is refused
    assert bpy.ops.style.label_rename(index=1, name="Baroque") == {"FINISHED"}
    assert assigned() == {"Chair": "Baroque", "Stool": "Baroque", "Table": "Style 1"}
    with pytest.raises(RuntimeError, match="already a style label 'Style 1'"):
        bpy.ops.style.label_rename(index=1, name="Style 1")
    # editing the name in the list (the property itself) follows too, and stays unique
    s.labels[0].name = "Gothic"
    assert assigned()["Table"] == "Gothic"
    s.labels[0].name = "Baroque"
    assert [n for n, _ in labels_of(scene)] == ["Baroque.001", "Baroque"]
    assert assigned()["Table"] == "Baroque.001"

    assert bpy.ops.style.label_color(index=1, color=(0.0, 0.5, 1.0, 1.0)) == {"FINISHED"}
    assert labels_of(scene)[1][1] == (0.0, 0.5, 1.0, 1.0)

    select("Stool", active="Stool")
    assert bpy.ops.style.label_clear() == {"FINISHED"}
    assert assigned() == {"Chair": "Baroque", "Table": "Baroque.001"}
    assert not bpy.ops.style.label_clear.poll()          # Stool has no label any more

    s.active_label_index = 1
    assert bpy.ops.style.label_remove() == {"FINISHED"}
    assert [n for n, _ in labels_of(scene)] == ["Baroque.001"]
    assert assigned() == {"Table": "Baroque.001"}


def test_poll_messages_explain(scene):
    """Unavailable operators say why (poll_message_set), in words a person can act on."""
    select()
    for op, words in ((bpy.ops.style.label_assign, "no style labels"),
                      (bpy.ops.style.triplet_remove, "no triplets"),
                      (bpy.ops.style.analyse, "at least two mesh objects"),
                      (bpy.ops.style.select_cluster, "No style clusters"),
                      (bpy.ops.style.decimate, "Select the mesh objects")):
        assert not op.poll()
        with pytest.raises(RuntimeError, match=words):
            op()
    # triplet_add stays available to scripts (names as arguments); without them it explains
    with pytest.raises(RuntimeError, match="Set A, B and C in the panel"):
        bpy.ops.style.triplet_add()


def test_triplets_from_panel_selection_and_names(scene):
    s = scene.style_coanalysis
    # from the panel's three fields
    s.triplet_a, s.triplet_b, s.triplet_c = (bpy.data.objects[n] for n in ("Chair", "Stool", "Bed"))
    assert bpy.ops.style.triplet_add() == {"FINISHED"}
    # the same again is not added twice
    assert bpy.ops.style.triplet_add() == {"CANCELLED"}
    # from the selection: active is A, the other two are B and C by name
    s.triplet_a = None
    select("Table", "Bed", "Chair", active="Table")
    assert bpy.ops.style.triplet_add() == {"FINISHED"}
    # by name (scripts)
    assert bpy.ops.style.triplet_add(a="Bed", b="Table", c="Chair") == {"FINISHED"}
    assert triplets_of(scene) == [("Chair", "Stool", "Bed"), ("Table", "Bed", "Chair"),
                                  ("Bed", "Table", "Chair")]
    with pytest.raises(RuntimeError, match="three different objects"):
        bpy.ops.style.triplet_add(a="Bed", b="Bed", c="Chair")
    with pytest.raises(RuntimeError, match="'Cam' is not a mesh"):
        bpy.ops.style.triplet_add(a="Bed", b="Cam", c="Chair")

    assert bpy.ops.style.triplet_swap(index=0) == {"FINISHED"}
    assert triplets_of(scene)[0] == ("Chair", "Bed", "Stool")
    assert bpy.ops.style.triplet_remove(index=1) == {"FINISHED"}
    assert triplets_of(scene) == [("Chair", "Bed", "Stool"), ("Bed", "Table", "Chair")]
    # pointers, not names: renaming an object keeps its constraints
    bpy.data.objects["Chair"].name = "Armchair"
    assert triplets_of(scene)[0] == ("Armchair", "Bed", "Stool")


def test_constraints_survive_save_and_reload(scene, tmp_path):
    bpy.ops.style.label_add(name="Ming")
    bpy.ops.style.label_color(color=(0.1, 0.2, 0.3, 1.0))
    select("Chair", "Bed", active="Chair")
    bpy.ops.style.label_assign()
    bpy.ops.style.triplet_add(a="Chair", b="Bed", c="Table")
    scene.style_coanalysis.n_representatives = 40
    path = str(tmp_path / "constraints.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert len(bpy.context.scene.style_coanalysis.labels) == 0
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    assert labels_of(scene) == [("Ming", (0.1, 0.2, 0.3, 1.0))]
    assert assigned() == {"Chair": "Ming", "Bed": "Ming"}
    assert triplets_of(scene) == [("Chair", "Bed", "Table")]
    assert scene.style_coanalysis.n_representatives == 40
    # renaming still follows after a reload (the previous name was stored too)
    assert bpy.ops.style.label_rename(index=0, name="Qing") == {"FINISHED"}
    assert assigned() == {"Chair": "Qing", "Bed": "Qing"}


def test_paper_defaults(scene):
    s = scene.style_coanalysis
    assert (s.n_representatives, s.max_rounds) == (50, 5)
    for name, value in (("eta", 0.2), ("lam", 20.0), ("beta", 0.05), ("gamma", 10.0),
                        ("mu", 0.07)):
        assert getattr(s, name) == pytest.approx(value)
