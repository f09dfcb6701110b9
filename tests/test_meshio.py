"""OBJ and truth files round-trip, accept what real OBJ files contain, and name the file on errors."""
import numpy as np
import pytest

from style_coanalysis import meshio, sample
from style_coanalysis.meshes import InputError, Mesh


def test_obj_round_trip_and_truth(tmp_path):
    m = sample.make_shape("lattice", "stool", 3, "stool_x")
    meshio.write_obj(m, tmp_path / "stool_x.obj")
    meshio.write_truth(m, tmp_path / "stool_x.npz")
    back = meshio.read_obj(tmp_path / "stool_x.obj")
    assert back.name == "stool_x"
    assert np.array_equal(back.faces, m.faces)
    assert np.allclose(back.vertices, m.vertices, atol=1e-5)
    t = meshio.read_truth(tmp_path / "stool_x.npz")
    assert t["style"] == "lattice" and t["category"] == "stool"
    assert np.array_equal(t["face_mask"], m.truth["face_mask"])


def test_colours_quads_negative_indices_and_slashes(tmp_path):
    p = tmp_path / "quad.obj"
    p.write_text("# a unit square as a quad and a triangle with relative indices\n"
                 "mtllib x.mtl\no thing\n"
                 "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 0.5 0.5 0.5\n"
                 "vt 0 0\nvn 0 0 1\n"
                 "f 1/1/1 2/1/1 3/1/1 4/1/1\n"
                 "v 0 0 1\n"
                 "f -1 -4//1 -3\n")
    m = meshio.read_obj(p)
    assert m.vertices.shape == (5, 3)
    assert np.allclose(m.vertices[2], [1, 1, 0])           # colours were not read as coordinates
    assert m.faces.tolist() == [[0, 1, 2], [0, 2, 3], [4, 1, 2]]


@pytest.mark.parametrize("text", ["v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
                                  "v 0 0 0\nv 1 0 zero\n",
                                  "\x00\x01binary junk\n",
                                  "v 0 0 0\n"])
def test_bad_file_names_the_file(tmp_path, text):
    p = tmp_path / "broken_chair.obj"
    p.write_text(text)
    with pytest.raises(InputError, match="broken_chair.obj"):
        meshio.read_obj(p)


def test_truth_of_mesh_without_truth(tmp_path):
    m = Mesh("plain", np.eye(3), [[0, 1, 2]])
    meshio.write_truth(m, tmp_path / "plain.npz")
    t = meshio.read_truth(tmp_path / "plain.npz")
    assert t["style"] == "" and t["face_mask"].size == 0


def test_normalised_frame_survives_scaling_and_a_file_round_trip(tmp_path):
    """The renderer redraws lines for a change of a float32's last bit, so `normalise` rounds
    the frame to a grid: the same shape scaled by 1.0000001, or written to an OBJ file (6
    decimals) and read back, gives the same normalised vertices but for the rare one that sat
    on a grid line, moved by one step. Unrounded, most vertices differ."""
    from style_coanalysis.meshes import NORMALISED_GRID, normalisation, normalise
    moved, moved_unrounded, total = 0, 0, 0
    for m in sample.generate(8, seed=0):
        ref = normalise(m)
        steps = ref.vertices.astype(np.float64) / NORMALISED_GRID
        assert np.array_equal(steps, np.round(steps))                 # on the grid
        scaled = Mesh(m.name, m.vertices.astype(np.float64) * 1.0000001, m.faces)
        meshio.write_obj(m, tmp_path / f"{m.name}.obj")
        c0, r0 = normalisation(m)
        unrounded = ((m.vertices.astype(np.float64) - c0) / r0).astype(np.float32)
        for other in (scaled, meshio.read_obj(tmp_path / f"{m.name}.obj")):
            d = np.abs(normalise(other).vertices.astype(np.float64) - ref.vertices).max(axis=1)
            assert d.max() <= NORMALISED_GRID * 1.01
            moved += int((d > 0).sum())
            c, r = normalisation(other)
            raw = ((other.vertices.astype(np.float64) - c) / r).astype(np.float32)
            moved_unrounded += int((raw != unrounded).any(axis=1).sum())
            total += len(m.vertices)
    assert moved <= 0.01 * total, (moved, total)
    assert moved_unrounded >= 0.5 * total, (moved_unrounded, total)


def test_where_a_shape_sits_changes_only_its_world_frame():
    """`Mesh.origin` (an object's location, kept apart from its float32 coordinates) moves the
    normalised frame's centre and nothing the drawings see; the same offset written into the
    coordinates costs them bits, and some vertices move on the grid."""
    from style_coanalysis.meshes import normalisation, normalise, up_to_z
    m = sample.generate(1, seed=3)[0]
    where = np.array([1000.0, -250.0, 40.0])
    far = Mesh(m.name, m.vertices, m.faces, origin=where)
    assert far.content_hash() == m.content_hash()
    for up in ("z", "y"):
        assert np.array_equal(normalise(far, up).vertices, normalise(m, up).vertices)
        (c0, r0), (c, r) = normalisation(m, up), normalisation(far, up)
        assert r == r0 and np.allclose(c - c0, up_to_z(where[None], up)[0])
    baked = Mesh(m.name, m.vertices.astype(np.float64) + where, m.faces)
    assert not np.array_equal(normalise(baked).vertices, normalise(m).vertices)
