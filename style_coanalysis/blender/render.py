"""Line drawings of one normalised mesh from the paper's 12 cameras (section 3), plus seeds.

`draw_shape(mesh, settings)` builds a temporary scene (never the user's), renders every view with
the chosen renderer, tests seed visibility by ray casting, removes everything it made and
returns a `ShapeDrawings` (the "zbuffer" renderer makes no scene and casts no BVH ray):

- "freestyle" (faithful): Cycles on the CPU, 1 sample, only the strokes (the shape invisible to
  Cycles' rays and a transparent film: the PNG's alpha is the ink). Silhouettes, borders, dihedral
  creases, optionally suggestive contours (paper: DeCarlo et al. + dihedral feature lines).
- "lineart" (fast): one Grease Pencil Line Art modifier per camera (each with its own custom
  camera, so one depsgraph evaluation computes a quarter turn's views); the strokes' 3D points
  are projected with the rig and rasterised as 1-pixel polylines. No render engine; no
  suggestive contours.

- "zbuffer" (fastest): no Blender at all (`zbuffer.ShapeBuffers`): one depth buffer per view
  rasterised in numpy; the same silhouettes, borders and creases as Freestyle, and the seeds'
  visibility, are lookups in it. No suggestive contours.

Cameras match the `rig.Rig`'s exactly (location, orientation, horizontal field of view), so its
matrices describe the Blender renders to within a pixel (tested with `world_to_camera_view`).
Every renderer draws view v with camera `rig.camera_of(v)` and the shape turned into the view's
frame (`rig.into_quarter`): a shape turned by a quarter is drawn exactly as the original.
"""
from __future__ import annotations

import contextlib
import math
import os
import sys
import tempfile

import bpy
import numpy as np
from mathutils import Matrix
from mathutils.bvhtree import BVHTree
from skimage import draw, io

from ..drawings import ShapeDrawings
from ..meshes import InputError, Mesh
from ..params import DrawingSettings
from ..rig import Rig, project
from ..seeds import sample_seeds
from ..zbuffer import ShapeBuffers

PREFIX = "SCA_tmp_"
VISIBILITY_TOL_PX = 1.0     # depth slack of the visibility test, in pixels' worth at the point
NORMALISED_REACH = 1.001    # a normalised mesh's farthest vertex from the origin (float32 slack)


def rig_for(settings: DrawingSettings) -> Rig:
    return Rig(n_views=settings.n_views, elevation_deg=settings.elevation_deg,
               image_size=settings.image_size)


# ---------------------------------------------------------------- quiet C-level output
@contextlib.contextmanager
def quiet_fds():
    """Send the process's C-level stdout/stderr to a temporary file for the block.

    Freestyle prints thousands of "edge appears twice" warnings and the render operator prints
    "Saved: ..." lines straight to file descriptors 1 and 2, past Python's sys.stdout. Yields the
    log file so a failure can quote it.
    """
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    saved = [os.dup(1), os.dup(2)]
    log = tempfile.TemporaryFile(mode="w+b")
    try:
        os.dup2(log.fileno(), 1)
        os.dup2(log.fileno(), 2)
        yield log
    finally:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
            sys.stderr.flush()
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(saved[0])
        os.close(saved[1])
        log.close()


# ---------------------------------------------------------------- temporary scene
class TempScene:
    """A scene holding the mesh and the rig's cameras; `close()` removes every datablock made.

    The mesh object holds the shape turned into one quarter's frame at a time (`show_quarter`),
    one mesh datablock per quarter."""

    def __init__(self, mesh: Mesh, rig: Rig):
        self._made: list = []           # (collection name, datablock name) in creation order
        self.rig = rig
        self.scene = self._new("scenes", PREFIX + "scene")
        r = self.scene.render
        r.resolution_x = r.resolution_y = rig.image_size
        r.resolution_percentage = 100
        r.pixel_aspect_x = r.pixel_aspect_y = 1.0
        self.quarter_meshes = [self._mesh_data(rig.into_quarter(mesh.vertices, q), mesh.faces, q)
                               for q in range(rig.quarters)]
        self.mesh_object = self._new("objects", PREFIX + "shape", self.quarter_meshes[0])
        self.scene.collection.objects.link(self.mesh_object)
        self.cameras = self._cameras(rig)

    def show_quarter(self, quarter: int) -> None:
        """Give the mesh object the shape turned into `quarter`'s frame."""
        if self.mesh_object.data != self.quarter_meshes[quarter]:
            self.mesh_object.data = self.quarter_meshes[quarter]

    def _new(self, collection: str, name: str, *args):
        block = getattr(bpy.data, collection).new(name, *args)
        self._made.append((collection, block.name))
        return block

    def _mesh_data(self, vertices: np.ndarray, faces: np.ndarray, quarter: int):
        me = self._new("meshes", f"{PREFIX}mesh{quarter}")
        n, m = len(vertices), len(faces)
        me.vertices.add(n)
        me.vertices.foreach_set("co", vertices.astype(np.float32).ravel())
        me.loops.add(3 * m)
        me.loops.foreach_set("vertex_index", faces.astype(np.int32).ravel())
        me.polygons.add(m)
        me.polygons.foreach_set("loop_start", np.arange(0, 3 * m, 3, dtype=np.int32))
        me.update(calc_edges=True)
        # Renderers only: validation may drop degenerate faces, which the seeds never see.
        me.validate(verbose=False)
        return me

    def _cameras(self, rig: Rig) -> list:
        cams = []
        for i, (frame, loc) in enumerate(zip(rig.camera_frames(), rig.camera_locations())):
            data = self._new("cameras", f"{PREFIX}cam{i:02d}")
            data.type = "PERSP"
            data.sensor_fit = "HORIZONTAL"
            data.angle = rig.fov
            data.clip_start = 0.01
            data.clip_end = 100.0
            ob = self._new("objects", f"{PREFIX}cam{i:02d}", data)
            # Blender cameras look down their local -Z with +Y up: columns right, up, -forward.
            m = np.eye(4)
            m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = frame[0], frame[1], -frame[2], loc
            ob.matrix_world = Matrix(m.tolist())
            self.scene.collection.objects.link(ob)
            cams.append(ob)
        self.scene.camera = cams[0]
        return cams

    def close(self) -> None:
        """Remove objects first (they use the data), then the scene, then the rest."""
        order = {"objects": 0, "scenes": 1}
        for collection, name in sorted(reversed(self._made), key=lambda cn: order.get(cn[0], 2)):
            coll = getattr(bpy.data, collection)
            block = coll.get(name)
            if block is not None:
                coll.remove(block)
        self._made.clear()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# ---------------------------------------------------------------- Freestyle
# Freestyle's style module (SCRIPT mode): what its parameter editor builds for one line set of
# visible silhouettes, borders and creases in a new line style (sampling 10, black, 1 px centred,
# plain chaining within an object), with compiled predicates and shaders in place of the editor's
# Python ones (its nested selection predicates, per-vertex thickness shader and chaining stop
# test): the same pixels in every view (tests/test_render.py), a view 4-11% faster.
STYLE_MODULE = """
from freestyle.chainingiterators import ChainSilhouetteIterator
from freestyle.functions import CurveNatureF1D
from freestyle.predicates import FalseUP1D, QuantitativeInvisibilityUP1D, TrueUP1D
from freestyle.shaders import ConstantColorShader, ConstantThicknessShader, SamplingShader
from freestyle.types import Nature, Operators, UnaryPredicate1D

KINDS = {kinds}


class OfKind(UnaryPredicate1D):
    def __init__(self):
        UnaryPredicate1D.__init__(self)
        self.nature = CurveNatureF1D()

    def __call__(self, edge):
        return bool(self.nature(edge) & KINDS)


Operators.select(QuantitativeInvisibilityUP1D(0))
Operators.select(OfKind())
# the iterator keeps to the selection, so no edge it reaches stops a chain
Operators.bidirectional_chain(ChainSilhouetteIterator(), FalseUP1D())
Operators.create(TrueUP1D(), [SamplingShader(10.0), ConstantColorShader(0.0, 0.0, 0.0, 1.0),
                              ConstantThicknessShader(1.0)])
"""


def _setup_freestyle(ts: TempScene, settings: DrawingSettings, threads: int) -> None:
    sc = ts.scene
    r = sc.render
    r.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.samples = 1
    sc.cycles.use_denoising = False
    sc.cycles.use_adaptive_sampling = False
    if threads > 0:
        r.threads_mode = "FIXED"
        r.threads = threads
    r.film_transparent = True
    r.use_freestyle = True
    r.line_thickness_mode = "ABSOLUTE"
    r.line_thickness = 1.0
    r.image_settings.file_format = "PNG"
    r.image_settings.color_mode = "RGBA"
    r.image_settings.color_depth = "8"
    sc.view_settings.view_transform = "Standard"
    vl = sc.view_layers[0]
    vl.use_freestyle = True
    # only the strokes: Cycles' rays pass through the shape (Freestyle still reads it), so the
    # transparent film leaves the PNG's alpha the ink; the same pixels as a Holdout material
    # on the shape, 3-10% faster a view
    for ray in ("camera", "diffuse", "glossy", "transmission", "volume_scatter", "shadow"):
        setattr(ts.mesh_object, f"visible_{ray}", False)
    fs = vl.freestyle_settings
    fs.mode = "SCRIPT"
    fs.crease_angle = math.radians(settings.crease_angle_deg)
    fs.use_culling = False
    fs.use_smoothness = False
    fs.use_suggestive_contours = bool(settings.suggestive_contours)
    kinds = ["SILHOUETTE", "BORDER", "CREASE"] + \
        (["SUGGESTIVE_CONTOUR"] if settings.suggestive_contours else [])
    text = ts._new("texts", PREFIX + "lines.py")
    text.write(STYLE_MODULE.format(kinds=" | ".join(f"Nature.{k}" for k in kinds)))
    for old in list(fs.modules):
        fs.modules.remove(old)
    fs.modules.new().script = text


def _render_freestyle_steps(ts: TempScene, settings: DrawingSettings, threads: int):
    """Generator: one view rendered per step (yields the view index); returns the images.

    C-level output is silenced per view, never across a yield: between steps Blender's own
    output (and the caller's) must reach the terminal."""
    with quiet_fds():
        _setup_freestyle(ts, settings, threads)
    sc = ts.scene
    size = settings.image_size
    rig = ts.rig
    images = np.zeros((rig.n_views, size, size), np.float32)
    with tempfile.TemporaryDirectory(prefix="sca_render_") as tmp:
        for v in range(rig.n_views):
            ts.show_quarter(rig.quarter_of(v))
            sc.camera = ts.cameras[rig.camera_of(v)]
            path = os.path.join(tmp, f"view_{v:02d}.png")
            sc.render.filepath = path
            with quiet_fds() as log:
                bpy.ops.render.render(write_still=True, scene=sc.name)
                if not os.path.exists(path):
                    log.seek(0)
                    tail = log.read()[-2000:].decode("utf-8", "replace")
                    raise RuntimeError(f"Freestyle wrote no image for view {v}:\n{tail}")
            rgba = io.imread(path)
            images[v] = rgba[..., 3].astype(np.float32) / 255.0
            yield v
    return images


def _render_freestyle(ts: TempScene, settings: DrawingSettings, threads: int) -> np.ndarray:
    return _run(_render_freestyle_steps(ts, settings, threads))


def _run(gen):
    """Run a step generator to its end; its return value."""
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            return stop.value


# ---------------------------------------------------------------- Line Art
LINEART_MIN_BLENDER = (4, 3, 0)     # Grease Pencil v3 and its Line Art modifier


def check_renderer(renderer: str) -> None:
    """Refuse a renderer this Blender cannot run, before any work (InputError)."""
    if renderer == "lineart" and bpy.app.version < LINEART_MIN_BLENDER:
        need = ".".join(map(str, LINEART_MIN_BLENDER[:2]))
        raise InputError(f"the Line Art renderer needs Blender {need} or later (this is "
                         f"{bpy.app.version_string}): use the Freestyle renderer")


def _setup_lineart(ts: TempScene, settings: DrawingSettings):
    # Blender 4.3-4.5 keep Grease Pencil v3 data apart (v2 is `grease_pencils` there); 5.0 renamed it
    gp = ts._new("grease_pencils_v3" if hasattr(bpy.data, "grease_pencils_v3") else "grease_pencils",
                 PREFIX + "lines")
    mat = ts._new("materials", PREFIX + "gp_ink")
    bpy.data.materials.create_gpencil_data(mat)
    gp.materials.append(mat)
    ob = ts._new("objects", PREFIX + "lines", gp)
    ts.scene.collection.objects.link(ob)
    for v, cam in enumerate(ts.cameras):
        layer = gp.layers.new(f"view_{v:02d}")
        md = ob.modifiers.new(f"lineart_{v:02d}", "LINEART")
        md.source_type = "OBJECT"
        md.source_object = ts.mesh_object
        md.target_layer = layer.name
        md.target_material = mat
        md.use_custom_camera = True          # one modifier per camera: one evaluation a quarter
        md.source_camera = cam
        md.use_cache = False
        md.use_contour = True
        md.use_crease = True
        md.crease_threshold = math.radians(settings.crease_angle_deg)
        md.use_crease_on_smooth = True
        md.use_crease_on_sharp = True
        md.use_intersection = False
        md.use_material = False
        md.use_edge_mark = False
        md.use_loose = False
        md.smooth_tolerance = 0.0
        # Line Art nudges stroke points towards the (active) camera; we project the points with
        # the rig ourselves, so keep them exactly on the surface.
        md.stroke_depth_offset = 0.0
        md.use_offset_towards_custom_camera = True
        md.use_image_boundary_trimming = False
    return ob


def _drawing_polylines(drawing) -> list[np.ndarray]:
    """3D polylines of one evaluated Grease Pencil drawing (closed ones repeat their start)."""
    attrs = drawing.attributes
    pos_attr = attrs.get("position")
    if pos_attr is None or len(pos_attr.data) == 0:
        return []
    pos = np.empty(3 * len(pos_attr.data), np.float32)
    pos_attr.data.foreach_get("vector", pos)
    pos = pos.reshape(-1, 3)
    offsets = np.empty(len(drawing.curve_offsets), np.int32)
    drawing.curve_offsets.foreach_get("value", offsets)
    n_curves = len(offsets) - 1
    cyclic = np.zeros(n_curves, bool)
    cyc_attr = attrs.get("cyclic")
    if cyc_attr is not None and len(cyc_attr.data) == n_curves:
        cyc_attr.data.foreach_get("value", cyclic)
    lines = []
    for c in range(n_curves):
        pts = pos[offsets[c]:offsets[c + 1]]
        if cyclic[c] and len(pts) > 2:
            pts = np.vstack([pts, pts[:1]])
        lines.append(pts)
    return lines


def rasterise_polylines(polylines_px, size: int) -> np.ndarray:
    """1-pixel binary lines (size, size) float32 through (x, y) pixel polylines."""
    img = np.zeros((size, size), np.float32)
    for pts in polylines_px:
        pts = np.asarray(pts, np.float64)
        if len(pts) == 0 or not np.all(np.isfinite(pts)):
            continue
        ij = np.floor(pts).astype(np.int64)          # (col, row) of the pixel under each point
        if len(ij) == 1:
            ij = np.vstack([ij, ij])
        for (c0, r0), (c1, r1) in zip(ij[:-1], ij[1:]):
            rr, cc = draw.line(int(r0), int(c0), int(r1), int(c1))
            ok = (rr >= 0) & (rr < size) & (cc >= 0) & (cc < size)
            img[rr[ok], cc[ok]] = 1.0
    return img


def _render_lineart(ts: TempScene, settings: DrawingSettings, rig: Rig) -> np.ndarray:
    """Every view: one evaluation of the modifiers (one per camera) for each quarter turn."""
    ob = _setup_lineart(ts, settings)
    view_layer = ts.scene.view_layers[0]
    mats = rig.camera_matrices()
    size = settings.image_size
    images = np.zeros((rig.n_views, size, size), np.float32)
    for q in range(rig.quarters):
        ts.show_quarter(q)
        with quiet_fds():
            view_layer.update()       # (re)makes the scene's depsgraph, evaluates the modifiers
        ev = ob.evaluated_get(view_layer.depsgraph)
        layers = {layer.name: layer for layer in ev.data.layers}
        for c in range(rig.n_cameras):
            layer = layers.get(f"view_{c:02d}")
            frame = layer.current_frame() if layer is not None else None
            if frame is None:
                continue
            lines3d = _drawing_polylines(frame.drawing)
            lines_px = [project(mats[c:c + 1], pts)[0][0] for pts in lines3d]
            images[q * rig.n_cameras + c] = rasterise_polylines(lines_px, size)
    return images


# ---------------------------------------------------------------- visibility
def quarter_trees(mesh: Mesh, rig: Rig) -> list[BVHTree]:
    """A BVH tree of the shape turned into each quarter's frame (`rig.into_quarter`)."""
    faces = mesh.faces.tolist()
    return [BVHTree.FromPolygons(rig.into_quarter(mesh.vertices, q).tolist(), faces,
                                 all_triangles=True) for q in range(rig.quarters)]


def ray_visibility(trees: list, rig: Rig, points: np.ndarray, own_face=None) -> np.ndarray:
    """(V, N) bool: is each point the first thing each view's camera ray to it meets?

    `trees` from `quarter_trees`: each view casts in its own frame, as it is drawn. A ray from
    the camera centre to the point counts it visible when it hits nothing (grazing rays can
    slip past the point's own edge), hits at least the point's depth minus about one pixel's
    worth of depth (`VISIBILITY_TOL_PX`; tighter loses points on their own triangles to
    floating-point error), or hits the triangle the point lies on (`own_face`, one index per
    point).
    """
    points = np.asarray(points, np.float64).reshape(-1, 3)
    faces = None if own_face is None else np.asarray(own_face)
    if not len(points):
        return np.zeros((rig.n_views, 0), bool)
    locs = rig.camera_locations()
    return np.stack([_ray_view(trees[rig.quarter_of(v)], locs[rig.camera_of(v)], rig.focal_px,
                               rig.into_quarter(points, rig.quarter_of(v)), faces)
                     for v in range(rig.n_views)])


def ray_seen_by_any(trees: list, rig: Rig, points: np.ndarray, own_face) -> np.ndarray:
    """(N,) bool: `ray_visibility(...).any(axis=0)`, casting each view's rays only to the
    points no earlier view saw (the seeds' candidates, 3,600 for the analysis' 90 seeds: about
    half the rays)."""
    points = np.asarray(points, np.float64).reshape(-1, 3)
    faces = np.asarray(own_face)
    locs = rig.camera_locations()
    seen = np.zeros(len(points), bool)
    for v in range(rig.n_views):
        rest = np.flatnonzero(~seen)
        if len(rest) == 0:
            break
        q = rig.quarter_of(v)
        seen[rest] = _ray_view(trees[q], locs[rig.camera_of(v)], rig.focal_px,
                               rig.into_quarter(points[rest], q), faces[rest])
    return seen


def _ray_view(tree: BVHTree, loc, focal_px: float, points: np.ndarray, faces) -> np.ndarray:
    """(N,) bool: `ray_visibility` for the camera at `loc`."""
    d = points - loc
    dist = np.linalg.norm(d, axis=1)
    origin = tuple(loc)
    rc = tree.ray_cast
    hit_d = np.full(len(points), np.inf)
    hit_f = np.full(len(points), -1, np.int64)
    for i, dr in enumerate((d / dist[:, None]).tolist()):
        _, _, idx, dh = rc(origin, dr)
        if idx is not None:
            hit_d[i], hit_f[i] = dh, idx
    ok = hit_d >= dist - VISIBILITY_TOL_PX * dist / focal_px
    if faces is not None:
        ok |= hit_f == faces
    return ok


# ---------------------------------------------------------------- entry point
def check_normalised(mesh: Mesh) -> None:
    """Refuse a mesh outside the unit sphere (`meshes.normalise` puts every shape in it): the
    rig's cameras would sit inside it, and a depth buffer of triangles spanning the camera
    plane once ran the process out of memory (a raw voxel model 53 units across)."""
    reach = float(np.linalg.norm(np.asarray(mesh.vertices, np.float64), axis=1).max(initial=0.0))
    if reach > NORMALISED_REACH:
        raise InputError(f"'{mesh.name}' reaches {reach:.3g} units from the origin: draw "
                         "shapes normalised into the unit sphere (meshes.normalise)")


def draw_lines(mesh: Mesh, settings: DrawingSettings, threads: int = 0) -> np.ndarray:
    """The (V, H, W) ink images alone, with the chosen renderer (no seeds, no visibility)."""
    check_normalised(mesh)
    rig = rig_for(settings)
    if settings.renderer == "zbuffer":
        return np.concatenate([b.lines(settings.crease_angle_deg)
                               for b in quarter_buffers(mesh, rig)])
    with TempScene(mesh, rig) as ts:
        if settings.renderer == "freestyle":
            return _render_freestyle(ts, settings, threads)
        return _render_lineart(ts, settings, rig)


RENDERERS = ("freestyle", "lineart", "zbuffer")


def quarter_buffers(mesh: Mesh, rig: Rig) -> list[ShapeBuffers]:
    """The depth buffers of the shape turned into each quarter's frame, for its cameras: view v
    is camera `rig.camera_of(v)` of buffers `rig.quarter_of(v)`."""
    out: list[ShapeBuffers] = []
    for q in range(rig.quarters):
        out.append(ShapeBuffers(rig.into_quarter(mesh.vertices, q), mesh.faces,
                                rig.camera_matrices(), rig.camera_locations(), rig.image_size,
                                rig.focal_px, turned_from=out[0] if out else None))
    return out


def _zbuffer_steps(mesh: Mesh, settings: DrawingSettings, rig: Rig):
    """`draw_shape_steps` for the "zbuffer" renderer: every answer from one set of depth buffers."""
    buffers = quarter_buffers(mesh, rig)
    yield "depth buffers"

    def seen_somewhere(points, faces):
        seen = np.zeros(len(points), bool)
        for q, b in enumerate(buffers):
            rest = np.flatnonzero(~seen)
            seen[rest] = b.points_seen_by_any(rig.into_quarter(points[rest], q), faces[rest])
        return seen

    seeds, seed_faces = sample_seeds(mesh, settings.n_seeds, settings.seed, keep=seen_somewhere)
    seed_visible = np.concatenate([b.points_visible(rig.into_quarter(seeds, q), seed_faces)
                                   for q, b in enumerate(buffers)])
    yield "seeds"
    images = np.concatenate([b.lines(settings.crease_angle_deg) for b in buffers])
    seed_pixels, _ = rig.project_views(seeds)
    yield f"views {rig.n_views}/{rig.n_views}"
    return ShapeDrawings(
        name=mesh.name, images=images, cameras=rig.matrices(), seeds=seeds, seed_faces=seed_faces,
        seed_visible=seed_visible, seed_pixels=seed_pixels.astype(np.float32))


def draw_shape(mesh: Mesh, settings: DrawingSettings, threads: int = 0) -> ShapeDrawings:
    """Drawings, seeds and visibility of an already normalised mesh (`meshes.normalise`).

    `threads` caps Cycles' render threads (0: Blender's automatic choice); parallel workers
    pass 1 so that they do not fight over the cores.
    """
    return _run(draw_shape_steps(mesh, settings, threads))


def draw_shape_steps(mesh: Mesh, settings: DrawingSettings, threads: int = 0):
    """`draw_shape` as a generator of short steps, for Blender's main thread.

    Yields a short description of the step just done ("seeds", "view 3/12"); returns the
    ShapeDrawings. Each step is the seeds (a ray cast per candidate and camera until one sees it), one rendered view or the
    Line Art evaluations (all views at once, they are fast), so a caller that runs one step per UI
    event never blocks the interface for long. Closing the generator removes the temporary
    scene.
    """
    if settings.renderer not in RENDERERS:
        raise InputError(f"unknown renderer '{settings.renderer}' (use {', '.join(RENDERERS)})")
    if settings.suggestive_contours and settings.renderer != "freestyle":
        raise InputError(f"the {settings.renderer} renderer draws no suggestive contours: "
                         "use freestyle")
    if len(mesh.faces) == 0:
        raise InputError(f"'{mesh.name}' has no faces")
    check_normalised(mesh)
    rig = rig_for(settings)
    if settings.renderer == "zbuffer":
        return (yield from _zbuffer_steps(mesh, settings, rig))
    trees = quarter_trees(mesh, rig)
    n_views = rig.n_views

    def seen_somewhere(points, faces):
        return ray_seen_by_any(trees, rig, points, faces)

    seeds, seed_faces = sample_seeds(mesh, settings.n_seeds, settings.seed, keep=seen_somewhere)
    seed_visible = ray_visibility(trees, rig, seeds, own_face=seed_faces)
    yield "seeds"
    seed_pixels, _ = rig.project_views(seeds)
    with TempScene(mesh, rig) as ts:
        yield "scene"
        if settings.renderer == "freestyle":
            steps = _render_freestyle_steps(ts, settings, threads)
            while True:
                try:
                    v = next(steps)
                except StopIteration as stop:
                    images = stop.value
                    break
                yield f"view {v + 1}/{n_views}"
        else:
            images = _render_lineart(ts, settings, rig)
            yield f"views {n_views}/{n_views}"
    return ShapeDrawings(
        name=mesh.name, images=images, cameras=rig.matrices(), seeds=seeds, seed_faces=seed_faces,
        seed_visible=seed_visible, seed_pixels=seed_pixels.astype(np.float32))
