"""Real voxel furniture -> closed, smooth, upright meshes with their expert style labels."""
import os

import numpy as np
import pytest

from style_coanalysis.evaluation import voxels
from style_coanalysis.meshes import InputError, validate

ROOT = voxels.resolve_root()
pytestmark = pytest.mark.skipif(not os.path.isdir(ROOT), reason="hu2017_vox data not present")


def edge_use_counts(faces):
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    return np.unique(e, axis=0, return_counts=True)[1]


@pytest.mark.parametrize("stem", ["Children_bed_1", "Ming_chair_1", "Japanese_table_1"])
def test_watertight_labelled_upright(stem):
    m = voxels.voxel_mesh(os.path.join(ROOT, "voxel", stem + ".binvox"))
    validate(m)
    assert m.name == stem
    assert np.all(edge_use_counts(m.faces) == 2)
    assert 500 < len(m.vertices) < 20000
    style, category = stem.split("_")[:2]
    assert m.truth == {"style": style, "category": category}
    if category == "table":          # the top is the widest slice, and it is at the top
        z = m.vertices[:, 2]
        upper = m.vertices[z > z.min() + 0.8 * np.ptp(z)]
        lower = m.vertices[z < z.min() + 0.2 * np.ptp(z)]
        assert np.ptp(upper[:, 0]) * np.ptp(upper[:, 1]) > 0 and len(upper) > 2 * len(lower)


def test_smoothing_removes_staircase():
    p = os.path.join(ROOT, "voxel", "Ming_chair_1.binvox")
    raw, smooth = voxels.voxel_mesh(p, smooth_iters=0), voxels.voxel_mesh(p, smooth_iters=10)

    def bent_share(m):  # share of edges bent by more than 30 degrees (dihedral below 150)
        v, f = m.vertices.astype(float), m.faces
        n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
        order = np.lexsort(e.T[::-1])
        fid = np.tile(np.arange(len(f)), 3)[order]
        pairs = fid.reshape(-1, 2)                              # watertight: edges come in pairs
        cosang = np.einsum("ij,ij->i", n[pairs[:, 0]], n[pairs[:, 1]])
        return np.mean(cosang < np.cos(np.radians(180 - 150)))

    # marching cubes on a binary grid bends edges by 45 and 90 degrees everywhere (staircase)
    assert bent_share(smooth) < 0.75 * bent_share(raw)
    extent = np.ptp(raw.vertices, axis=0)
    assert np.allclose(np.ptp(smooth.vertices, axis=0), extent, rtol=0.15)   # no shrinking


def test_stratified_subset():
    ms = voxels.load_hu2017(per_class=3, seed=1)
    styles = [m.truth["style"] for m in ms]
    assert sorted(set(styles)) == ["Children", "European", "Japanese", "Ming"]
    assert all(styles.count(s) == 3 for s in set(styles))
    assert len({m.truth["category"] for m in ms}) >= 3
    assert [m.name for m in voxels.load_hu2017(per_class=3, seed=1)] == [m.name for m in ms]


def test_bad_binvox_names_file(tmp_path):
    p = tmp_path / "junk.binvox"
    p.write_bytes(b"#binvox 1\ndim 2 2 2\ndata\n\x01\x05")
    with pytest.raises(InputError, match="junk.binvox"):
        voxels.voxel_mesh(p)


def test_the_default_root_is_found_from_any_working_folder(tmp_path, monkeypatch):
    # the relative default is tried from the working folder, then from the repository root
    here = os.path.realpath(ROOT)
    monkeypatch.chdir(tmp_path)
    assert os.path.realpath(voxels.resolve_root()) == here
