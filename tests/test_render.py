"""Line renderers against geometry we can reason about: a cube and a stepped block.

Expected lines come from the meshes themselves (feature edges projected with the rig); ink must
sit on them and nowhere else, hidden edges must stay blank, and the two renderers must agree.
"""
import numpy as np
import pytest
from scipy import ndimage

bpy = pytest.importorskip("bpy")

from style_coanalysis.meshes import Mesh, normalise  # noqa: E402
from style_coanalysis.params import DrawingSettings  # noqa: E402
from style_coanalysis.rig import Rig, project  # noqa: E402

pytestmark = pytest.mark.blender


def extrude(profile, tris, depth, name):
    """Closed prism: a planar (x, z) profile polygon (CCW) with cap triangles, extruded along y."""
    profile = np.asarray(profile, float)
    n = len(profile)
    front = np.column_stack([profile[:, 0], np.zeros(n), profile[:, 1]])
    back = front + [0.0, depth, 0.0]
    verts = np.vstack([front, back])
    faces = [[a, b, c] for a, b, c in tris]                     # y = 0 cap faces -y
    faces += [[n + a, n + c, n + b] for a, b, c in tris]         # y = depth cap faces +y
    for i in range(n):
        j = (i + 1) % n
        faces += [[i, n + i, n + j], [i, n + j, j]]
    return Mesh(name, verts, np.asarray(faces))


def cube():
    return extrude([(0, 0), (1, 0), (1, 1), (0, 1)], [(0, 1, 2), (0, 2, 3)], 1.0, "cube")


def stepped_block():
    """An L-shaped prism: a low wide step and a tall back part (creases at 90 and 270 degrees)."""
    profile = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2), (0, 1)]
    tris = [(0, 1, 2), (0, 2, 3), (0, 3, 6), (6, 3, 4), (6, 4, 5)]
    return extrude(profile, tris, 1.2, "step")


def face_normals(mesh):
    v = mesh.vertices.astype(float)[mesh.faces]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def feature_edges(mesh, angle_deg=30.0):
    """Edges whose two faces' normals differ by more than angle_deg: (E, 2) vertices, (E, 2) faces."""
    edges = {}
    for f, tri in enumerate(mesh.faces):
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            edges.setdefault((min(a, b), max(a, b)), []).append(f)
    n = face_normals(mesh)
    out_e, out_f = [], []
    for e, fs in edges.items():
        assert len(fs) == 2, "test meshes are closed manifolds"
        if np.degrees(np.arccos(np.clip(n[fs[0]] @ n[fs[1]], -1, 1))) > angle_deg:
            out_e.append(e)
            out_f.append(fs)
    return np.asarray(out_e), np.asarray(out_f)


def edge_samples(mesh, edges, k=80, trim=0.12):
    """Points along each edge, ends trimmed by `trim` (corners are ambiguous): (E, k, 3)."""
    t = np.linspace(trim, 1.0 - trim, k)[None, :, None]
    a = mesh.vertices[edges[:, 0]].astype(float)[:, None]
    b = mesh.vertices[edges[:, 1]].astype(float)[:, None]
    return a + t * (b - a)


def near(mask, px, radius):
    """For (n, 2) pixel points: is any True pixel of `mask` within `radius` pixels?"""
    dist = ndimage.distance_transform_edt(~mask)
    col = np.clip(np.floor(px[:, 0]).astype(int), 0, mask.shape[1] - 1)
    row = np.clip(np.floor(px[:, 1]).astype(int), 0, mask.shape[0] - 1)
    return dist[row, col] <= radius


def expected_lines(mesh, drawings, trim=0.12):
    """Per view: (visible sample pixels, hidden sample pixels) of the feature edges.

    Visibility of edge samples by ray casting a BVH of the mesh (the same kind of test the
    renderer uses for seeds, checked on its own in test_far_side_seed_is_invisible).
    """
    from style_coanalysis.blender.render import quarter_trees, ray_visibility
    rig = Rig()
    edges, _ = feature_edges(mesh)
    pts = edge_samples(mesh, edges, trim=trim).reshape(-1, 3)
    vis = ray_visibility(quarter_trees(mesh, rig), rig, pts)
    pix, _ = project(drawings.cameras, pts)
    return [(pix[v][vis[v]], pix[v][~vis[v]]) for v in range(len(pix))]


SHAPES = {"cube": cube, "step": stepped_block}
RENDERERS = ("freestyle", "lineart", "zbuffer")


@pytest.fixture(scope="module")
def drawn():
    """Each test shape drawn once by each renderer (module scope keeps the suite quick)."""
    from style_coanalysis.blender.render import draw_shape
    bpy.ops.wm.read_factory_settings(use_empty=True)
    out = {}
    for name, make in SHAPES.items():
        mesh = normalise(make())
        for renderer in RENDERERS:
            out[name, renderer] = (mesh, draw_shape(mesh, DrawingSettings(renderer=renderer)))
    return out


def pixel_mask(px, size=200):
    mask = np.zeros((size, size), bool)
    px = px[np.isfinite(px).all(axis=1)]
    cols, rows = np.floor(px[:, 0]).astype(int), np.floor(px[:, 1]).astype(int)
    ok = (rows >= 0) & (rows < size) & (cols >= 0) & (cols < size)
    mask[rows[ok], cols[ok]] = True
    return mask


@pytest.mark.parametrize("renderer", RENDERERS)
@pytest.mark.parametrize("shape", list(SHAPES))
def test_ink_on_visible_edges_and_nowhere_else(drawn, shape, renderer):
    mesh, d = drawn[shape, renderer]
    assert d.images.shape == (12, 200, 200) and d.images.dtype == np.float32
    assert 0.0 <= d.images.min() and d.images.max() <= 1.0
    whole_edges = expected_lines(mesh, d, trim=0.0)
    for v, (vis_px, hid_px) in enumerate(expected_lines(mesh, d)):
        ink = d.images[v] > 0.25
        lines = pixel_mask(whole_edges[v][0])
        # every visible feature edge is drawn, within 1 px
        hit = near(ink, vis_px, 1.5)
        assert hit.mean() > 0.95, (v, hit.mean())
        # every ink pixel lies on a visible edge (within 2 px): no stray or hidden lines
        rows, cols = np.nonzero(ink)
        on_edge = near(lines, np.column_stack([cols + 0.5, rows + 0.5]), 2.5)
        assert on_edge.mean() > 0.97, (v, on_edge.mean())
        # hidden edge samples away from every visible edge stay blank
        far = ~near(lines, hid_px, 4.0)
        if far.any():
            assert not near(ink, hid_px[far], 1.0).any(), v


def test_far_side_seed_is_invisible():
    from style_coanalysis.blender.render import quarter_trees, ray_visibility
    mesh = normalise(cube())
    h = float(mesh.vertices[:, 0].max())           # half-size after normalisation
    near_pt = [h, 0.0, 0.0]                        # centre of the +x face, facing camera 0
    far_pt = [-h, 0.0, 0.0]                        # centre of the -x face
    vis = ray_visibility(quarter_trees(mesh, Rig()), Rig(), np.array([near_pt, far_pt]))
    assert vis[0].tolist() == [True, False]
    assert vis[6].tolist() == [False, True]        # camera 6 sits on the -x side


@pytest.mark.parametrize("renderer", RENDERERS)
def test_seed_visibility_matches_facing_on_cube(drawn, renderer):
    """On a convex shape a surface point is visible exactly when its face faces the camera
    (up to the one-pixel depth slack: points within ~a pixel of a cube edge may go either way)."""
    mesh, d = drawn["cube", renderer]
    normals = face_normals(mesh)[d.seed_faces]
    to_cam = Rig().locations()[:, None, :] - d.seeds[None].astype(float)
    facing = np.einsum("vsk,sk->vs", to_cam, normals) > 1e-6
    h = float(mesh.vertices.max())
    # distance to the nearest cube edge: second-smallest gap to the faces' planes
    to_edge = np.sort(h - np.abs(d.seeds.astype(float)), axis=1)[:, 1]
    clear = to_edge > 0.03
    assert clear.sum() >= 20
    assert d.seed_visible.shape == (12, 30)
    assert np.array_equal(d.seed_visible[:, clear], facing[:, clear])
    assert 0.2 < d.seed_visible.mean() < 0.8
    pix, depth = project(d.cameras, d.seeds)
    assert np.allclose(d.seed_pixels, pix, atol=1e-3) and (depth > 0).all()


def test_same_input_same_output(drawn):
    from style_coanalysis.blender.render import draw_shape
    mesh, first = drawn["step", "freestyle"]
    again = draw_shape(mesh, DrawingSettings(renderer="freestyle"))
    for field in ("images", "seeds", "seed_faces", "seed_visible", "seed_pixels"):
        assert np.array_equal(getattr(first, field), getattr(again, field)), field
    other = draw_shape(mesh, DrawingSettings(renderer="lineart", seed=1))
    assert not np.array_equal(other.seeds, first.seeds)


def f_score(a, b, radius=2.0):
    """Symmetric agreement of two ink masks: precision/recall of ink within `radius` px."""
    da = ndimage.distance_transform_edt(~a)
    db = ndimage.distance_transform_edt(~b)
    precision = (db[a] <= radius).mean()
    recall = (da[b] <= radius).mean()
    return 2 * precision * recall / (precision + recall)


@pytest.mark.parametrize("other", ["lineart", "zbuffer"])
@pytest.mark.parametrize("shape", list(SHAPES))
def test_renderers_agree(drawn, shape, other):
    _, fs = drawn[shape, "freestyle"]
    _, la = drawn[shape, other]
    scores = [f_score(fs.images[v] > 0.25, la.images[v] > 0.25) for v in range(12)]
    assert min(scores) > 0.85, scores


@pytest.mark.parametrize("shape", list(SHAPES))
def test_zbuffer_visibility_is_the_ray_casts(drawn, shape):
    """The depth buffers' visibility of surface points against a BVH ray cast per point and
    camera, on 2,000 points spread over the faces (the seeds' test)."""
    from style_coanalysis.blender.render import quarter_buffers, quarter_trees, ray_visibility
    mesh, _ = drawn[shape, "zbuffer"]
    rng = np.random.default_rng(0)
    faces = rng.integers(0, len(mesh.faces), 2000)
    w = rng.dirichlet(np.ones(3), 2000)
    points = np.einsum("nk,nkd->nd", w, mesh.vertices[mesh.faces[faces]].astype(float))
    rig = Rig()
    seen = np.concatenate([b.points_visible(rig.into_quarter(points, q), own_face=faces)
                           for q, b in enumerate(quarter_buffers(mesh, rig))])
    rays = ray_visibility(quarter_trees(mesh, rig), rig, points, own_face=faces)
    assert 0.2 < rays.mean() < 0.8
    assert np.array_equal(seen, rays), (seen != rays).sum()


@pytest.mark.parametrize("renderer", RENDERERS)
def test_a_shape_turned_by_a_quarter_is_drawn_exactly_with_its_views_shifted(renderer):
    """Turned by 90 degrees about the up axis, a shape's 12 views are the original's shifted by
    three, to the bit: the drawings, the seeds' visibility and pixels, and the seeds themselves
    turned (issue 11: the partition must not change when a user turns an asset)."""
    from style_coanalysis.blender.render import draw_shape
    from style_coanalysis.rig import quarter_turn
    from style_coanalysis.sample import generate
    shape = generate(size=6, seed=3)[5]
    turned = Mesh(shape.name, quarter_turn(shape.vertices, 1), shape.faces)
    settings = DrawingSettings(renderer=renderer, n_seeds=30)
    a, b = (draw_shape(normalise(m), settings) for m in (shape, turned))
    assert a.images.sum() > 100 and not np.array_equal(a.images, np.roll(a.images, 3, axis=0))
    np.testing.assert_array_equal(b.images, np.roll(a.images, 3, axis=0))
    np.testing.assert_array_equal(b.seeds, quarter_turn(a.seeds, 1))
    np.testing.assert_array_equal(b.seed_faces, a.seed_faces)
    np.testing.assert_array_equal(b.seed_visible, np.roll(a.seed_visible, 3, axis=0))
    np.testing.assert_array_equal(b.seed_pixels, np.roll(a.seed_pixels, 3, axis=0))


def test_zbuffer_open_surface_seen_from_behind():
    """A single-sided plane is drawn from both sides: back faces are only left out of the
    depth buffers when the surface is closed."""
    from style_coanalysis.blender.render import draw_shape
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    up = normalise(Mesh("up", v, [[0, 1, 2], [0, 2, 3]]))
    down = normalise(Mesh("down", v, [[0, 2, 1], [0, 3, 2]]))
    a = draw_shape(up, DrawingSettings(renderer="zbuffer"))
    b = draw_shape(down, DrawingSettings(renderer="zbuffer"))
    assert a.images.sum() > 0 and np.array_equal(a.images, b.images)
    assert a.seed_visible.all() and np.array_equal(a.seed_visible, b.seed_visible)


@pytest.mark.parametrize("renderer", ["zbuffer", "lineart"])
def test_only_freestyle_draws_suggestive_contours(renderer):
    """Line Art and the depth buffers have no suggestive contours: asked for, they refuse
    rather than draw without them."""
    from style_coanalysis.blender.render import draw_shape
    from style_coanalysis.meshes import InputError
    n_scenes = len(bpy.data.scenes)
    with pytest.raises(InputError, match=f"the {renderer} renderer draws no suggestive contours"):
        draw_shape(normalise(cube()), DrawingSettings(renderer=renderer, suggestive_contours=True))
    assert len(bpy.data.scenes) == n_scenes              # refused before making a scene


def test_no_leaks_and_user_scene_untouched():
    from style_coanalysis.blender.render import draw_shape
    bpy.ops.wm.read_factory_settings(use_empty=True)
    user_scene = bpy.context.scene.name
    mesh = normalise(cube())
    draw_shape(mesh, DrawingSettings(renderer="freestyle"))      # first call makes 'Render Result'

    def counts():
        return {attr: len(getattr(bpy.data, attr)) for attr in dir(bpy.data)
                if isinstance(getattr(bpy.data, attr, None), bpy.types.bpy_prop_collection)}
    before = counts()
    for renderer in RENDERERS:
        draw_shape(mesh, DrawingSettings(renderer=renderer))
    assert counts() == before
    assert bpy.context.scene.name == user_scene
    assert len(bpy.context.scene.objects) == 0


def test_zbuffer_version_is_in_its_cache_key_only(monkeypatch):
    """Changing the zbuffer renderer (its VERSION) changes its drawings' cache key and no other
    renderer's, so the others' cache entries stay valid."""
    from style_coanalysis import zbuffer
    from style_coanalysis.blender.batch import drawing_version
    from style_coanalysis.cache import CODE_VERSION, cache_key
    mesh = normalise(cube())
    keys = {r: cache_key(mesh, DrawingSettings(renderer=r), drawing_version(DrawingSettings(
        renderer=r))) for r in RENDERERS}
    monkeypatch.setattr(zbuffer, "VERSION", zbuffer.VERSION + "-next")
    for r in RENDERERS:
        again = cache_key(mesh, DrawingSettings(renderer=r), drawing_version(DrawingSettings(
            renderer=r)))
        assert (again == keys[r]) == (r != "zbuffer"), r
    assert keys["freestyle"] == cache_key(mesh, DrawingSettings(renderer="freestyle"), CODE_VERSION)


@pytest.mark.parametrize("suggestive", [False, True])
def test_style_module_draws_what_the_line_set_editor_draws(suggestive, monkeypatch):
    """The Freestyle style module (compiled predicates and shaders) puts ink on exactly the
    pixels Freestyle's own parameter editor does for the line set it stands for: visible
    silhouettes, borders and creases (and suggestive contours) in a new line style."""
    from style_coanalysis.blender import render
    from style_coanalysis.sample import generate
    settings = DrawingSettings(renderer="freestyle", n_views=3, suggestive_contours=suggestive)
    mesh = normalise(generate(size=6, seed=3)[5])
    ours = render.draw_lines(mesh, settings)
    setup = render._setup_freestyle

    def editor(ts, settings, threads):
        setup(ts, settings, threads)
        fs = ts.scene.view_layers[0].freestyle_settings
        fs.mode = "EDITOR"
        ls = fs.linesets.new("lines")
        ls.linestyle = ts._new("linestyles", "style")
        ls.linestyle.color, ls.linestyle.thickness = (0.0, 0.0, 0.0), 1.0
        ls.select_by_visibility, ls.visibility, ls.select_by_edge_types = True, "VISIBLE", True
        for kind in ("silhouette", "border", "crease", "suggestive_contour", "ridge_valley",
                     "material_boundary", "contour", "external_contour", "edge_mark"):
            setattr(ls, f"select_{kind}", kind in ("silhouette", "border", "crease") or
                    (suggestive and kind == "suggestive_contour"))
    monkeypatch.setattr(render, "_setup_freestyle", editor)
    theirs = render.draw_lines(mesh, settings)
    assert ours.sum() > 100
    np.testing.assert_array_equal(ours, theirs)


@pytest.mark.parametrize("renderer", RENDERERS)
def test_mesh_outside_the_unit_sphere_is_refused_by_name(renderer):
    """A mesh drawn without `normalise` (here 50 units across) gets an error naming it, before
    any scene is made, rather than cameras inside it."""
    from style_coanalysis.blender.render import draw_shape
    from style_coanalysis.meshes import InputError
    big = cube()
    big = Mesh("big_cube", big.vertices * 50.0, big.faces)
    with pytest.raises(InputError, match="'big_cube' reaches .* normalise"):
        draw_shape(big, DrawingSettings(renderer=renderer))
    draw_shape(normalise(big), DrawingSettings(renderer=renderer))
