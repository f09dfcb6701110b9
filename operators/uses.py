"""Operators that put the last analysis to use: select the shapes closest in style to the active
one, and select the shapes worth labelling next. Both read the style space the analysis stored
in the scene (`space_store`), so they work after save and reload without re-drawing; they change
only the selection and the lists the Results panel shows (scene custom properties)."""
import json

import bpy
from bpy.props import IntProperty

from ..style_coanalysis.blender import space_store, writeback
from ..style_coanalysis.suggest import suggest

SIMILAR_KEY = "style_similar"       # {"query": name, "ranked": [[name, distance, cluster], ...]}
SUGGESTED_KEY = "style_suggested"   # [[name, reason], ...]


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


CLASSES = (STYLE_OT_select_similar, STYLE_OT_suggest_labels)
