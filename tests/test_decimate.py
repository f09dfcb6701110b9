"""Style-preserving decimation through Blender's Decimate modifier: at the same overall triangle
count it must keep more of the style region than plain decimation, and it must report honestly
what it reached."""

import re

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender



@pytest.fixture
def dec(ext):
    from style_coanalysis_ext.style_coanalysis.blender import decimate
    return decimate


def bumpy_grid(name="Bumpy", n=40, seed=0):
    """A triangulated height field with random bumps everywhere (so every collapse has a cost)
    and a style group of weight 1 on the quarter x > 0.5, y > 0."""
    rng = np.random.default_rng(seed)
    xs = np.linspace(-1, 1, n + 1)
    X, Y = np.meshgrid(xs, xs)
    Z = 0.03 * rng.standard_normal(X.shape)
    verts = np.stack([X.ravel(), Y.ravel(), Z.ravel()], 1)
    faces = []
    for j in range(n):
        for i in range(n):
            a, b = j * (n + 1) + i, j * (n + 1) + i + 1
            c, d = (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i
            faces += [(a, b, c), (a, c, d)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts.tolist(), [], faces)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    style = np.flatnonzero((verts[:, 0] > 0.0) & (verts[:, 1] > 0.0))
    group = obj.vertex_groups.new(name="style_weight")
    group.add(style.tolist(), 1.0, "REPLACE")
    return obj


@pytest.fixture
def grid(ext):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return bumpy_grid()


def test_style_preserving_keeps_more_style_triangles_at_equal_count(dec, grid):
    styled = dec.add_decimate(grid, ratio=0.3, strength=1.0, style_preserving=True)
    assert styled["triangles"] < 0.6 * styled["triangles_before"]         # it did decimate
    # weight-1 vertices are never collapsed: the whole style region is kept
    assert styled["style_triangles"] >= 0.95 * styled["style_triangles_before"]
    plain = dec.match_plain_to(grid, styled["triangles"])
    assert abs(plain["triangles"] - styled["triangles"]) <= 0.01 * styled["triangles"]
    assert [m.name for m in grid.modifiers] == [dec.PLAIN_MODIFIER]     # never stacked
    assert plain["style_triangles"] < 0.7 * styled["style_triangles"]


def test_unreachable_ratio_is_reported_not_hidden(dec, grid):
    res = dec.add_decimate(grid, ratio=0.05, strength=1.0)
    assert res["requested_triangles"] == round(0.05 * res["triangles_before"])
    # a quarter of the surface is protected, so 5% cannot be reached
    assert res["triangles"] > 3 * res["requested_triangles"]
    assert res["triangles"] >= res["style_triangles"] >= 0.95 * res["style_triangles_before"]


def test_strength_zero_ignores_the_style_group(dec, grid):
    off = dec.add_decimate(grid, ratio=0.3, strength=0.0)
    assert off["triangles"] == pytest.approx(0.3 * off["triangles_before"], rel=0.02)
    assert off["style_triangles"] < 0.6 * off["style_triangles_before"]


def test_rerun_updates_one_modifier_and_apply_bakes_it(dec, grid):
    dec.add_decimate(grid, ratio=0.5, strength=1.0)
    dec.add_decimate(grid, ratio=0.4, strength=1.0)
    assert [m.name for m in grid.modifiers] == [dec.STYLE_MODIFIER]
    assert grid.modifiers[0].ratio == pytest.approx(0.4)
    assert grid.modifiers[0].invert_vertex_group
    res = dec.add_decimate(grid, ratio=0.4, strength=1.0, apply=True)
    assert len(grid.modifiers) == 0
    assert dec.triangle_counts(grid) == (res["triangles"], res["style_triangles"])
    assert grid.vertex_groups.get("style_weight") is not None       # weights survive on the mesh


def test_needs_the_style_group(dec, grid):
    grid.vertex_groups.remove(grid.vertex_groups["style_weight"])
    with pytest.raises(ValueError, match="'Bumpy' has no 'style_weight'"):
        dec.add_decimate(grid, 0.3, 1.0)


def test_operator_reports_counts(ext, grid, capfd):
    grid.select_set(True)
    bpy.context.view_layer.objects.active = grid
    before = len(grid.data.polygons)
    capfd.readouterr()
    assert bpy.ops.style.decimate(ratio=0.3, strength=1.0, style_preserving=True) == {"FINISHED"}
    styled = grid.modifiers[0].face_count
    said = capfd.readouterr()
    # the status line gives the count the modifier reached, of the mesh's, and the style regions'
    assert re.search(rf"'Bumpy' style-preserving: {styled} of {before} triangles \(asked "
                     rf"{round(0.3 * before)}\), style regions \d+ of \d+", said.out + said.err)
    assert bpy.ops.style.decimate(ratio=0.3, style_preserving=False, match_style=True) == \
        {"FINISHED"}
    assert [m.name for m in grid.modifiers] == ["Plain Decimate"]
    assert abs(grid.modifiers[0].face_count - styled) <= 0.01 * styled
    assert bpy.ops.style.decimate_remove() == {"FINISHED"}
    assert len(grid.modifiers) == 0
    assert not bpy.ops.style.decimate_remove.poll()


def test_soft_protection_reaches_the_ratio_and_collapses_style_last(dec, grid):
    soft = dec.add_decimate(grid, ratio=0.15, strength=1.0, hard=False)
    assert soft["triangles"] == pytest.approx(0.15 * soft["triangles_before"], rel=0.02)
    # 480 triangles left, 760 were style: style is decimated too, but keeps the larger share
    plain = dec.match_plain_to(grid, soft["triangles"])
    assert soft["style_triangles"] > 1.5 * plain["style_triangles"]
    dec.remove_decimate(grid)
    assert grid.vertex_groups.get(dec.SOFT_GROUP) is None and len(grid.modifiers) == 0


def test_split_decimation_reaches_the_ratio_and_the_plain_part_takes_the_reduction(dec, grid):
    split = dec.add_split_decimate(grid, ratio=0.3)
    assert split["triangles"] == pytest.approx(0.3 * split["triangles_before"], rel=0.03)
    assert [m.name for m in grid.modifiers] == list(dec.SPLIT_MODIFIERS)
    # the plain three quarters go down to a tenth; the style quarter keeps the rest of the budget
    plain_kept = split["triangles"] - split["style_triangles"]
    assert plain_kept < 0.2 * (split["triangles_before"] - split["style_triangles_before"])
    kept = split["style_triangles"]
    dec.remove_decimate(grid)
    assert len(grid.modifiers) == 0 and all(grid.vertex_groups.get(g) is None for g in dec.SPLIT_GROUPS)
    plain = dec.match_plain_to(grid, split["triangles"])
    assert kept > 1.5 * plain["style_triangles"]
