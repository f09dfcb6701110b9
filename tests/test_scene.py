"""Blender adapter with the real bpy module: objects <-> Mesh, .blend and mesh-file import."""
import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from style_coanalysis import meshio, sample  # noqa: E402
from style_coanalysis.blender import scene  # noqa: E402
from style_coanalysis.meshes import InputError  # noqa: E402

pytestmark = pytest.mark.blender


@pytest.fixture
def clean():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    yield
    bpy.ops.wm.read_factory_settings(use_empty=True)


@pytest.fixture(scope="module")
def shapes():
    return [sample.make_shape("turned", "stool", 1, "stool_a"),
            sample.make_shape("cabriole", "table", 2, "table_b")]


def test_round_trip_with_world_transform_and_truth(clean, shapes):
    names = scene.objects_from_meshes(shapes, "Shapes")
    obj = bpy.data.objects[names[0]]
    obj.location = (1.0, -2.0, 0.5)
    obj.scale = (2.0, 2.0, 3.0)
    dg = bpy.context.evaluated_depsgraph_get()
    back = scene.mesh_from_object(obj, dg)
    src = shapes[0]
    assert back.name == names[0] == "stool_a"
    assert len(back.vertices) == len(src.vertices)       # vertex order kept: results map 1:1
    assert np.allclose(back.vertices + back.origin, src.vertices * [2, 2, 3] + [1, -2, 0.5],
                       atol=1e-4)
    assert np.allclose(back.origin, [1, -2, 0.5])
    assert np.array_equal(np.sort(back.faces, axis=1), np.sort(src.faces, axis=1))
    assert back.truth["style"] == "turned" and back.truth["category"] == "stool"
    assert np.array_equal(back.truth["face_mask"], src.truth["face_mask"])


def test_an_object_reads_the_same_wherever_it_sits(clean, shapes, tmp_path):
    """An object's location is kept apart from its coordinates (Mesh.origin), so moving it, or
    a .blend laying the shapes out on a grid, gives the same float32 vertices bit for bit."""
    names = scene.objects_from_meshes(shapes, "Shapes")
    obj = bpy.data.objects[names[0]]
    obj.location = (1000.0, -250.0, 40.0)
    moved = scene.mesh_from_object(obj, bpy.context.evaluated_depsgraph_get())
    assert np.array_equal(moved.vertices, shapes[0].vertices)
    assert moved.content_hash() == shapes[0].content_hash()          # the same drawings
    assert np.allclose(moved.origin, [1000.0, -250.0, 40.0])
    scene.write_blend(shapes, tmp_path / "grid.blend", "Grid")
    back = {m.name: m for m in scene.meshes_from_blend(tmp_path / "grid.blend")}
    assert all(np.array_equal(back[s.name].vertices, s.vertices) for s in shapes)
    assert len({tuple(m.origin) for m in back.values()}) == len(shapes)   # laid out apart


def test_parts_of_one_file_keep_their_places(clean, shapes, tmp_path):
    """A file's mesh objects are joined into one shape where the file puts them (glTF nodes
    carry their own translations): the parts keep their places relative to each other."""
    names = scene.objects_from_meshes(shapes, "Export")
    places = [(5.0, 0.0, 0.0), (-3.0, 2.0, 1.0)]
    for n, p in zip(names, places):
        bpy.data.objects[n].location = p
        bpy.data.objects[n].select_set(True)
    bpy.ops.export_scene.gltf(filepath=str(tmp_path / "two.glb"), use_selection=True,
                              export_format="GLB")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    got = scene.import_mesh_file(tmp_path / "two.glb")
    world = got.vertices + got.origin
    expected = np.concatenate([s.vertices + p for s, p in zip(shapes, places)])
    assert len(got.faces) == sum(len(s.faces) for s in shapes)
    assert np.allclose(world.min(0), expected.min(0), atol=1e-4)
    assert np.allclose(world.max(0), expected.max(0), atol=1e-4)


def test_blend_save_and_collections(clean, shapes, tmp_path):
    scene.objects_from_meshes(shapes[:1], "A")
    scene.objects_from_meshes(shapes[1:], "B")
    path = tmp_path / "two.blend"
    scene.save_blend(path)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert [m.name for m in scene.meshes_from_blend(path)] == ["stool_a", "table_b"]
    only_b = scene.meshes_from_blend(path, collection="B")
    assert [m.name for m in only_b] == ["table_b"] and only_b[0].truth["style"] == "cabriole"
    with pytest.raises(InputError, match="'Nope'"):
        scene.meshes_from_blend(path, collection="Nope")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.data.collections.new("Empty")
    scene.save_blend(tmp_path / "empty.blend")
    with pytest.raises(InputError, match="no mesh"):
        scene.meshes_from_blend(tmp_path / "empty.blend")


def test_import_folder_obj_ply_stl(clean, shapes, tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    meshio.write_obj(shapes[0], folder / "first.obj")
    # a PLY of two separate objects, exported by Blender itself: one shape, parts joined
    names = scene.objects_from_meshes(shapes, "Export")
    for n in names:
        bpy.data.objects[n].select_set(True)
    bpy.ops.wm.ply_export(filepath=str(folder / "second.ply"), export_selected_objects=True,
                          forward_axis="Y", up_axis="Z")
    bpy.ops.wm.stl_export(filepath=str(folder / "third.stl"), export_selected_objects=True,
                          forward_axis="Y", up_axis="Z")
    (folder / "notes.txt").write_text("not a mesh")
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    bpy.ops.wm.read_factory_settings(use_empty=True)
    got = scene.import_mesh_files(folder)
    assert [m.name for m in got] == ["first", "second", "third"]
    assert np.allclose(np.sort(got[0].vertices, axis=0), np.sort(shapes[0].vertices, axis=0),
                       atol=1e-4)                       # OBJ taken as Z-up, no axis change
    total_faces = sum(len(s.faces) for s in shapes)
    assert len(got[1].faces) == total_faces and len(got[2].faces) == total_faces
    lo = np.minimum(shapes[0].vertices.min(0), shapes[1].vertices.min(0))
    assert np.allclose(got[1].vertices.min(0), lo, atol=1e-4)
    assert len(bpy.data.objects) == 0                   # imported objects were removed again
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before


def test_bad_file_is_named(clean, tmp_path):
    folder = tmp_path / "bad"
    folder.mkdir()
    (folder / "ok.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (folder / "garbage.ply").write_bytes(b"ply\nformat nonsense\n\x00\x01\x02")
    with pytest.raises(InputError, match="garbage.ply"):
        scene.import_mesh_files(folder)
    with pytest.raises(InputError, match="nowhere"):
        scene.import_mesh_files(tmp_path / "nowhere")


def test_sample_command_writes_consistent_outputs(clean, tmp_path):
    from argparse import Namespace

    from style_coanalysis.blender import cmd_sample

    assert cmd_sample.run(Namespace(out=str(tmp_path), size=6, seed=2)) == 0
    rows = (tmp_path / "labels.csv").read_text().splitlines()
    assert rows[0] == "name,style,category" and len(rows) == 7
    name, style, category = rows[1].split(",")
    obj = meshio.read_obj(tmp_path / "meshes" / f"{name}.obj")
    truth = meshio.read_truth(tmp_path / "truth" / f"{name}.npz")
    assert (truth["style"], truth["category"]) == (style, category)
    assert truth["face_mask"].shape == (len(obj.faces),)
    from_blend = {m.name: m for m in scene.meshes_from_blend(tmp_path / "sample.blend")}
    assert len(from_blend) == 6
    b = from_blend[name]
    assert b.truth["style"] == style and np.array_equal(b.truth["face_mask"], truth["face_mask"])
    # the .blend lays shapes out on a grid: same shape up to a translation
    shift = b.vertices.mean(0) - obj.vertices.mean(0)
    assert np.allclose(b.vertices - shift, obj.vertices, atol=1e-3)
    with pytest.raises(InputError, match="size"):
        cmd_sample.run(Namespace(out=str(tmp_path / "x"), size=0, seed=0))
