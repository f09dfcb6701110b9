"""The camera rig of paper section 3, and Blender's cameras built from it."""
import math

import numpy as np
import pytest

from style_coanalysis.meshes import Mesh
from style_coanalysis.rig import Rig, project, quarter_turn


def test_twelve_views_every_30_degrees_at_30_degrees_up():
    rig = Rig()
    locs = rig.locations()
    assert locs.shape == (12, 3) and rig.matrices().shape == (12, 3, 4)
    az = np.degrees(np.arctan2(locs[:, 1], locs[:, 0])) % 360
    assert np.allclose(np.diff(az), 30.0)
    elev = np.degrees(np.arcsin(locs[:, 2] / np.linalg.norm(locs, axis=1)))
    assert np.allclose(elev, 30.0)
    assert np.allclose(np.linalg.norm(locs, axis=1), 3.0)


def test_centroid_projects_to_image_centre():
    pix, depth = project(Rig().matrices(), np.zeros((1, 3)))
    assert np.allclose(pix, 100.0) and np.allclose(depth, 3.0)


def test_known_points_project_where_the_pinhole_model_says():
    """View 0 sits on +x; its right axis is +y and its up axis is (-sin30, 0, cos30).
    A point 0.5 along either axis stays at depth 3, so it lands f * 0.5 / 3 px off centre,
    with f = 100 / tan(fov / 2) and sin(fov / 2) = 1.05 / 3."""
    a = 1.05 / 3.0
    f = 100.0 * math.sqrt(1 - a * a) / a
    s30, c30 = 0.5, math.sqrt(3) / 2
    pts = np.array([[0.0, 0.5, 0.0], [-0.5 * s30, 0.0, 0.5 * c30]])
    pix, depth = project(Rig().matrices()[:1], pts)
    assert np.allclose(depth, 3.0)
    assert np.allclose(pix[0, 0], [100 + f * 0.5 / 3, 100.0], atol=1e-6)   # right of centre
    assert np.allclose(pix[0, 1], [100.0, 100 - f * 0.5 / 3], atol=1e-6)   # above: smaller row


def test_unit_sphere_stays_inside_the_image():
    rng = np.random.default_rng(0)
    pts = rng.normal(size=(2000, 3))
    pts /= np.linalg.norm(pts, axis=1, keepdims=True)
    pix, _ = project(Rig().matrices(), pts)
    assert pix.min() > 0 and pix.max() < 200


def test_quarter_turns_are_exact_and_undo_each_other():
    rng = np.random.default_rng(2)
    pts = rng.normal(size=(500, 3)).astype(np.float32)
    turned = quarter_turn(pts, 1)
    assert turned.dtype == np.float32
    assert np.allclose(turned, pts @ np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]]).T)
    assert np.array_equal(quarter_turn(turned, -1), pts)
    assert np.array_equal(quarter_turn(pts, 4), pts) and np.array_equal(quarter_turn(pts, -3), turned)
    rig = Rig()
    for q in range(4):      # the turned shape in quarter q + 1's frame is the shape in quarter q's
        assert np.array_equal(rig.into_quarter(turned, (q + 1) % 4), rig.into_quarter(pts, q))


@pytest.mark.parametrize("n_views", [12, 8, 5])
def test_every_view_is_its_camera_seeing_the_shape_turned_into_it(n_views):
    """`project_views` (a camera of the first quarter, the points turned by quarters: what the
    renderers draw) is the projection of every view's own matrix; a rig whose views do not
    fall on the axes every quarter turn places a camera for every view."""
    rig = Rig(n_views=n_views)
    assert rig.n_cameras == (n_views // 4 if n_views % 4 == 0 else n_views)
    pts = np.random.default_rng(3).uniform(-0.7, 0.7, size=(100, 3))
    pix, depth = rig.project_views(pts)
    expected, exp_depth = project(rig.matrices(), pts)
    assert np.allclose(pix, expected, atol=1e-9) and np.allclose(depth, exp_depth, atol=1e-12)
    az = np.degrees(np.arctan2(rig.locations()[:, 1], rig.locations()[:, 0])) % 360
    assert np.allclose(az, np.arange(n_views) * 360.0 / n_views)


@pytest.mark.blender
def test_blender_cameras_match_the_rig():
    bpy = pytest.importorskip("bpy")
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    from style_coanalysis.blender.render import TempScene
    bpy.ops.wm.read_factory_settings(use_empty=True)
    rig = Rig()
    tri = Mesh("tri", [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]], [[0, 1, 2]])
    rng = np.random.default_rng(1)
    pts = rng.uniform(-0.7, 0.7, size=(20, 3))
    expected, depth = project(rig.camera_matrices(), pts)
    with TempScene(tri, rig) as ts:
        assert ts.scene.render.resolution_x == ts.scene.render.resolution_y == 200
        assert len(ts.cameras) == rig.n_cameras == 3
        for v, cam in enumerate(ts.cameras):
            got = []
            for p in pts:
                c = world_to_camera_view(ts.scene, cam, Vector(p))
                got.append([c.x * 200, (1.0 - c.y) * 200, c.z])     # Blender's y grows upwards
            got = np.asarray(got)
            assert np.abs(got[:, :2] - expected[v]).max() < 1.0, v
            assert np.allclose(got[:, 2], depth[v], atol=1e-4)
