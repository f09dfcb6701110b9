"""Everything the add-on stores in a .blend file, plus its preferences.

Stored in the file (so it survives save, reload and undo):
- `Scene.style_coanalysis` (`StyleSettings`): the style labels (name, colour), the triplet
  constraints, the analysis settings and the last run's clusters.
- `Object.style_coanalysis` (`StyleObjectSettings`): the label a person assigned to the object.

The analysis results on objects (cluster, predicted label, confidence, best view, and the
identified style of Identify Style from Drawings) are plain custom properties, with the vertex
groups and materials, written by `writeback.py`; the scene's custom properties hold the style
space (`space_store.py`) and the last Select Similar, Suggest and Identify answers
(`operators/uses.py`). They are readable without the add-on installed.

Objects are referenced by PointerProperty (triplets) or by name (label assignment is on the object
itself), never held in Python variables: undo frees `bpy_struct`s.
"""
from __future__ import annotations

import os

import bpy
from bpy.props import (BoolProperty, CollectionProperty, EnumProperty, FloatProperty,
                       FloatVectorProperty, IntProperty, PointerProperty, StringProperty)

from ..options import DEFAULTS, default, help_text

# The extension's root package ("bl_ext.<repo>.<id>" when installed): AddonPreferences are looked up
# under it. This module is <root>.style_coanalysis.blender.properties.
ROOT_PACKAGE = __package__.rsplit(".", 2)[0]

RENDERERS = (
    ("freestyle", "Freestyle", "Faithful line drawings (Cycles + Freestyle, slower)"),
    ("lineart", "Line Art", "Fast line drawings (Grease Pencil Line Art, no suggestive contours)"),
    ("zbuffer", "Depth Buffer", "Fastest: lines from depth buffers in numpy, no render engine"),
)

# The Advanced panel's properties: defaults and descriptions come from options.PARAMETERS, i.e.
# from params.AnalysisParams (the one place that holds the paper's values).
PARAMETER_PROPS = {"representatives": "n_representatives", "eta": "eta", "lam": "lam",
                   "beta": "beta", "gamma": "gamma", "mu": "mu", "rounds": "max_rounds"}
METHODS = (("default", "Default", "This extension's method (see the README)"),
           ("paper", "Paper", "The paper's method, sections 3-4.5 as written"))


def _param(option: str) -> dict:
    text = help_text(option).replace("--method paper", "the Paper method")
    return dict(default=default(option), description=text[:1].upper() + text[1:])


def default_cache_dir() -> str:
    """The cache folder (drawings, HOG maps, analyses, regions, dictionaries) used when the
    preference is empty.

    Installed as an extension: the extension's user folder (kept across upgrades, unlike the
    extension folder itself). Imported directly (tests, the command line): the user cache folder.
    Resolved when needed rather than at import so that importing never creates folders.
    """
    try:
        base = bpy.utils.extension_path_user(ROOT_PACKAGE, path="", create=True)
        return os.path.join(base, "cache")
    except (ValueError, RuntimeError, TypeError):
        from ..cache import default_cache_dir as core_default   # the command line's default
        return os.fspath(core_default())


def preferences(context=None):
    """The add-on preferences, or None when the package is not registered as an add-on."""
    context = context or bpy.context
    addon = context.preferences.addons.get(ROOT_PACKAGE)
    return addon.preferences if addon else None


def cache_dir(context=None) -> str:
    prefs = preferences(context)
    path = prefs.cache_dir if prefs and prefs.cache_dir else default_cache_dir()
    return bpy.path.abspath(path)


class StylePreferences(bpy.types.AddonPreferences):
    """Machine-level settings: they belong to the user, not to a .blend file."""

    bl_idname = ROOT_PACKAGE

    cache_dir: StringProperty(
        name="Cache Folder", subtype="DIR_PATH", default="",
        description="Where drawings, HOG maps, analysis results, style regions and "
                    "synthetic vocabularies are cached between runs (empty: the extension's "
                    "user folder)")
    renderer: EnumProperty(name="Default Renderer", items=RENDERERS, default="freestyle",
                           description="Line renderer used when a scene asks for the default")
    jobs: IntProperty(name="Jobs", default=1, min=0, max=64,
                      description="Parallel processes for per-shape work when Blender runs as a Python "
                                  "module (bpy); inside the Blender application shapes are "
                                  "drawn one at a time on its main thread (0: all cores)")

    def draw(self, context):
        col = self.layout.column()
        col.prop(self, "cache_dir")
        if not self.cache_dir:
            col.label(text=f"Default: {default_cache_dir()}", icon="INFO")
        col.prop(self, "renderer")
        col.prop(self, "jobs")


def _unique_label_name(labels, wanted: str, skip) -> str:
    names = {lab.name for lab in labels if lab.as_pointer() != skip.as_pointer()}
    if wanted not in names:
        return wanted
    i = 1
    while f"{wanted}.{i:03d}" in names:
        i += 1
    return f"{wanted}.{i:03d}"


def _label_name_changed(self, context):
    """Renaming a label in the list renames it on every object that carries it (labels are
    assigned by name). `stored_name` remembers the previous name; names stay unique."""
    if self.name == self.stored_name:
        return
    scene = self.id_data
    old = self.stored_name
    new = _unique_label_name(scene.style_coanalysis.labels, self.name or "Style", self)
    # Writing self.name re-enters this callback; stored_name is updated first so it returns early.
    self.stored_name = new
    if self.name != new:
        self.name = new
    if old:
        for obj in bpy.data.objects:
            ob_settings = getattr(obj, "style_coanalysis", None)
            if ob_settings is not None and ob_settings.label == old:
                ob_settings.label = new


class StyleLabel(bpy.types.PropertyGroup):
    """A style class a person can assign to shapes (semi-supervised analysis)."""

    name: StringProperty(name="Name", default="Style", update=_label_name_changed)
    stored_name: StringProperty(options={"HIDDEN"})
    color: FloatVectorProperty(name="Colour", subtype="COLOR", size=4, min=0.0, max=1.0,
                               default=(0.8, 0.5, 0.1, 1.0))


def _is_mesh(self, obj):
    return obj.type == "MESH"


class StyleTriplet(bpy.types.PropertyGroup):
    """"A is closer in style to B than to C". Pointers, not names: renaming keeps the constraint."""

    a: PointerProperty(name="A", type=bpy.types.Object, poll=_is_mesh)
    b: PointerProperty(name="B", type=bpy.types.Object, poll=_is_mesh)
    c: PointerProperty(name="C", type=bpy.types.Object, poll=_is_mesh)

    def names(self):
        """(a, b, c) object names, or None when an object was deleted."""
        if self.a is None or self.b is None or self.c is None:
            return None
        return (self.a.name, self.b.name, self.c.name)


class StyleCluster(bpy.types.PropertyGroup):
    """One style cluster of the last run (members carry `style_cluster` = cluster_id)."""

    cluster_id: IntProperty(name="Cluster")
    size: IntProperty(name="Size")
    label: StringProperty(name="Label", description="Label given to most labelled members, if any")


class StyleSettings(bpy.types.PropertyGroup):
    """Per-scene constraints, settings and last results."""

    labels: CollectionProperty(type=StyleLabel)
    active_label_index: IntProperty(name="Active Label", default=0)
    triplets: CollectionProperty(type=StyleTriplet)
    active_triplet_index: IntProperty(name="Active Triplet", default=0)
    clusters: CollectionProperty(type=StyleCluster)
    active_cluster_index: IntProperty(name="Active Cluster", default=0)
    last_report: StringProperty(name="Last Run", default="")

    # Triplet being composed in the panel.
    triplet_a: PointerProperty(name="A", type=bpy.types.Object, poll=_is_mesh,
                               description="The shape the constraint is about")
    triplet_b: PointerProperty(name="B", type=bpy.types.Object, poll=_is_mesh,
                               description="A shape closer in style to A")
    triplet_c: PointerProperty(name="C", type=bpy.types.Object, poll=_is_mesh,
                               description="A shape less close in style to A")

    # What and how to analyse.
    target: EnumProperty(name="Target", default="SELECTED", items=(
        ("SELECTED", "Selected", "The selected mesh objects"),
        ("COLLECTION", "Collection", "The mesh objects of a collection (and its children)")))
    target_collection: PointerProperty(name="Collection", type=bpy.types.Collection)
    renderer: EnumProperty(name="Renderer", default="PREFERENCES", items=(
        ("PREFERENCES", "Default", "The renderer chosen in the add-on preferences"),) + RENDERERS)
    up: EnumProperty(name="Up Axis", default="z", items=(("z", "Z", "Z up"), ("y", "Y", "Y up")))
    auto_clusters: BoolProperty(name="Automatic", default=True,
                                description="Choose the number of style clusters automatically")
    n_clusters: IntProperty(name="Clusters", default=2, min=2, max=100,
                            description="Number of style clusters (at most the number of shapes)")
    seed: IntProperty(name="Seed", default=0, min=0)

    # Paper parameters (Advanced).
    method: EnumProperty(name="Method", items=METHODS, default=DEFAULTS.method,
                         description="Which method analyses the shapes")
    n_representatives: IntProperty(name="Representatives", min=2, max=1000,
                                   **_param("representatives"))
    eta: FloatProperty(name="Eta", min=0.001, max=1.0, **_param("eta"))
    lam: FloatProperty(name="Lambda", min=0.0, **_param("lam"))
    beta: FloatProperty(name="Beta", min=0.0, precision=3, **_param("beta"))
    gamma: FloatProperty(name="Gamma", min=0.0, **_param("gamma"))
    mu: FloatProperty(name="Mu", min=0.0, max=1.0, precision=3, **_param("mu"))
    max_rounds: IntProperty(name="Rounds", min=1, max=50, **_param("rounds"))

    # Decimation.
    decimate_ratio: FloatProperty(name="Ratio", min=0.0, max=1.0, default=0.3, subtype="FACTOR",
                                  description="Fraction of triangles to keep (0.3: 70% reduction)")
    decimate_strength: FloatProperty(name="Strength", min=0.0, max=1000.0, soft_max=10.0,
                                     default=1.0,
                                     description="How strongly style weights raise collapse cost "
                                                 "(with Protect Fully, vertices of weight 1 are "
                                                 "never collapsed)")
    decimate_hard: BoolProperty(name="Protect Fully", default=True,
                                description="Never collapse vertices of style weight 1 (the ratio "
                                            "may be out of reach); off: collapse them last")
    decimate_apply: BoolProperty(name="Apply", default=False,
                                 description="Apply the modifier to the mesh instead of keeping it")

    def label_names(self):
        return [lab.name for lab in self.labels]


class StyleObjectSettings(bpy.types.PropertyGroup):
    """The label a person gave this object (by name; empty: unlabelled)."""

    label: StringProperty(name="Style Label", default="")


CLASSES = (StylePreferences, StyleLabel, StyleTriplet, StyleCluster, StyleSettings,
           StyleObjectSettings)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.style_coanalysis = PointerProperty(type=StyleSettings)
    bpy.types.Object.style_coanalysis = PointerProperty(type=StyleObjectSettings)


def unregister():
    del bpy.types.Object.style_coanalysis
    del bpy.types.Scene.style_coanalysis
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
