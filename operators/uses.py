"""Operators that put the analysis to use: select the shapes closest in style to the active one,
select the shapes worth labelling next, and identify each shape's style from labelled 2D
drawings. The first two read the style space the analysis stored in the scene (`space_store`),
so they work after save and reload without re-drawing; they change only the selection and the
lists the Results panel shows (scene custom properties). Identify runs its own analysis of the
Analyse panel's target meshes and writes only on them: the custom properties `style_identified`
and `style_identified_votes`, and the vertex group `style_identified_weight` (where on the mesh
the identified style lies, 1 = style region), after checking every object first, so an invalid
or failed run changes nothing."""
import json

import bpy
from bpy.props import IntProperty, StringProperty

from ..style_coanalysis.blender import space_store, writeback
from ..style_coanalysis.suggest import suggest

SIMILAR_KEY = "style_similar"       # {"query": name, "ranked": [[name, distance, cluster], ...]}
SUGGESTED_KEY = "style_suggested"   # [[name, reason], ...]
IDENTIFIED_KEY = writeback.IDENTIFIED_SCENE_KEY   # [[name, style, votes], ...]
IDENTIFIED_GROUP = writeback.IDENTIFIED_GROUP


def _space(cls, context):
    """The stored style space if its shapes are still here with their results (poll helper)."""
    if context.mode != "OBJECT":
        cls.poll_message_set("Switch to Object Mode to select objects")
        return None
    space = space_store.read_scene(context.scene)
    if space is None or not any(writeback.has_results(context.scene.objects.get(n))
                                for n in space.names):
        cls.poll_message_set("No style analysis in this scene yet: run Analyse Style")
        return None
    return space


def _select(context, names, active=None):
    for o in context.view_layer.objects:
        o.select_set(False)
    for n in names:
        obj = context.view_layer.objects.get(n)
        if obj is not None:
            obj.select_set(True)
    if active is not None:
        context.view_layer.objects.active = context.view_layer.objects.get(active)


def read_list(scene, key):
    """A list an operator stored for the panel, or None."""
    text = scene.get(key)
    try:
        return json.loads(text) if isinstance(text, str) else None
    except ValueError:
        return None


class STYLE_OT_select_similar(bpy.types.Operator):
    """Select the analysed shapes closest in style to the active object, across categories, and
    list them ranked in the Results panel"""

    bl_idname = "style.select_similar"
    bl_label = "Select Similar Style"
    bl_options = {"REGISTER", "UNDO"}

    count: IntProperty(name="Count", default=5, min=1, soft_max=50,
                       description="How many of the closest shapes to select")

    @classmethod
    def poll(cls, context):
        space = _space(cls, context)
        if space is None:
            return False
        obj = context.active_object
        if obj is None:
            cls.poll_message_set("Make one analysed object active")
            return False
        if obj.name not in space.names or not writeback.has_results(obj):
            cls.poll_message_set(f"'{obj.name}' was not in the last style analysis")
            return False
        return True

    def execute(self, context):
        space = space_store.read_scene(context.scene)
        query = context.active_object.name
        present = [n for n in space.names if n in context.view_layer.objects]
        ranked = [(n, d) for n, d in space.ranking(query) if n in present][:self.count]
        _select(context, [query] + [n for n, _ in ranked], active=query)
        context.scene[SIMILAR_KEY] = json.dumps({"query": query, "ranked": [
            [n, round(d, 4), int(space.clusters[space.index(n)])] for n, d in ranked]})
        self.report({"INFO"}, f"{len(ranked)} shapes closest in style to '{query}': "
                    + ", ".join(n for n, _ in ranked))
        return {"FINISHED"}


class STYLE_OT_suggest_labels(bpy.types.Operator):
    """Select the unlabelled shapes whose style label would help the analysis most, and show why
    in the Results panel"""

    bl_idname = "style.suggest_labels"
    bl_label = "Suggest Shapes to Label"
    bl_options = {"REGISTER", "UNDO"}

    count: IntProperty(name="Count", default=5, min=1, soft_max=50,
                       description="How many shapes to suggest")

    @classmethod
    def poll(cls, context):
        return _space(cls, context) is not None

    def execute(self, context):
        space = space_store.read_scene(context.scene)
        objects = context.scene.objects
        # labelled now: given to the analysis, or assigned in the Labels panel since
        labelled = [bool(space.label_given[i]) or (
            objects.get(n) is not None and objects[n].type == "MESH"
            and bool(objects[n].style_coanalysis.label)) for i, n in enumerate(space.names)]
        if all(labelled):
            self.report({"WARNING"}, "Every analysed shape carries a label: nothing to suggest")
            return {"CANCELLED"}
        picks = suggest(space, self.count, labelled=labelled)
        _select(context, [p.name for p in picks], active=picks[0].name)
        context.scene[SUGGESTED_KEY] = json.dumps([[p.name, p.reason] for p in picks])
        self.report({"INFO"}, "Label next: " + ", ".join(p.name for p in picks))
        return {"FINISHED"}


class STYLE_OT_identify_from_drawings(bpy.types.Operator):
    """Predict each target mesh's style from a folder of labelled line drawings (one subfolder
    per style, PNG or JPEG) and mark where it lies (vertex group style_identified_weight). Runs
    the analysis first: the interface waits until it is done"""

    bl_idname = "style.identify_from_drawings"
    bl_label = "Identify Style from Drawings"
    bl_options = {"REGISTER", "UNDO"}

    directory: StringProperty(name="Drawings", subtype="DIR_PATH",
                              description="Folder with one subfolder of drawings per style")

    @classmethod
    def poll(cls, context):
        from .analyse import target_names
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode")
            return False
        if len(target_names(context)) < 2:
            cls.poll_message_set("Select at least two meshes (or choose a collection) in Analyse")
            return False
        return True

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        from ..style_coanalysis import identify as ident
        from ..style_coanalysis.blender.cmd_identify import identify_job
        from ..style_coanalysis.meshes import InputError
        from .analyse import build_job
        try:
            drawings = ident.load_drawings(bpy.path.abspath(self.directory))  # checked first
            meshes, options, warnings, _ = build_job(context)
            run = identify_job(meshes, options, drawings)
            write_identified(context.scene, run)
        except (InputError, writeback.WritebackError) as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        for w in warnings:
            self.report({"WARNING"}, w)
        rows = [[shape.name, r.style, r.votes[r.style]]
                for shape, r in zip(run.job.shapes, run.found)]
        context.scene[IDENTIFIED_KEY] = json.dumps(rows)
        counts = {}
        for _, style, _ in rows:
            counts[style] = counts.get(style, 0) + 1
        marked = sum(int((loc.face_weights > 0.5).any()) for loc in run.regions)
        self.report({"INFO"}, f"{len(rows)} shapes identified: "
                    + ", ".join(f"{s} {n}" for s, n in sorted(counts.items()))
                    + f"; style regions on {marked} (vertex group {IDENTIFIED_GROUP})")
        return {"FINISHED"}


def write_identified(scene, run):
    """The identification on its objects: properties per object, the region weights as vertex
    group IDENTIFIED_GROUP per mesh (a mesh shared by several analysed objects gets the mean of
    their weights, as writeback does for style_weight). Every object is checked first
    (writeback's check: present, a mesh, not linked, same vertex count), so a refusal changes
    nothing."""
    from collections import defaultdict
    from types import SimpleNamespace

    import numpy as np
    shapes = [SimpleNamespace(name=s.name, vertex_weights=loc.weights)
              for s, loc in zip(run.job.shapes, run.regions)]
    writeback._check(scene, SimpleNamespace(shapes=shapes))
    by_mesh = defaultdict(list)
    for s in shapes:
        by_mesh[scene.objects[s.name].data.name].append(s)
    for group in by_mesh.values():
        weights = np.mean([np.asarray(s.vertex_weights, np.float32) for s in group], axis=0)
        writeback.set_group_weights(scene.objects[group[0].name], IDENTIFIED_GROUP,
                                    np.clip(weights, 0.0, 1.0))
    for shape, r in zip(run.job.shapes, run.found):
        obj = scene.objects[shape.name]
        style_key, votes_key = writeback.IDENTIFIED_KEYS
        obj[style_key] = r.style
        obj[votes_key] = json.dumps(r.votes)


CLASSES = (STYLE_OT_select_similar, STYLE_OT_suggest_labels, STYLE_OT_identify_from_drawings)
