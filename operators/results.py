"""Operators on the results of a run: select a cluster, accept a prediction as a label, look
through the best view, show or hide the style regions, clear everything the run wrote."""
import bpy
from bpy.props import BoolProperty, IntProperty
from mathutils import Matrix

from ..style_coanalysis.blender import writeback

CAMERA_NAME = "Style Best View"


def _has_results(obj):
    return writeback.has_results(obj)


class STYLE_OT_select_cluster(bpy.types.Operator):
    """Select the members of a style cluster"""

    bl_idname = "style.select_cluster"
    bl_label = "Select Cluster"
    bl_options = {"REGISTER", "UNDO"}

    cluster: IntProperty(name="Cluster", default=-1, description="Cluster id (-1: the active one)")
    extend: BoolProperty(name="Extend", default=False, description="Keep the current selection")

    @classmethod
    def poll(cls, context):
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode to select objects")
            return False
        if not len(context.scene.style_coanalysis.clusters):
            cls.poll_message_set("No style clusters yet: run Analyse Style")
            return False
        return True

    def execute(self, context):
        settings = context.scene.style_coanalysis
        cid = self.cluster
        if cid < 0:
            i = settings.active_cluster_index
            if not 0 <= i < len(settings.clusters):
                self.report({"ERROR"}, "No active cluster")
                return {"CANCELLED"}
            cid = settings.clusters[i].cluster_id
        members = [o for o in context.view_layer.objects if o.get("style_cluster") == cid]
        if not self.extend:
            for o in context.view_layer.objects:
                o.select_set(False)
        for o in members:
            o.select_set(True)
        if members:
            context.view_layer.objects.active = members[0]
        for i, item in enumerate(settings.clusters):
            if item.cluster_id == cid:
                settings.active_cluster_index = i
        self.report({"INFO"}, f"Cluster {cid}: {len(members)} objects selected")
        return {"FINISHED"}


class STYLE_OT_accept_prediction(bpy.types.Operator):
    """Make the predicted style label the active object's own label (a constraint for the next
    run)"""

    bl_idname = "style.accept_prediction"
    bl_label = "Accept Prediction"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        if not _has_results(obj):
            cls.poll_message_set("The active object has no style results")
            return False
        if not obj.get("style_label"):
            cls.poll_message_set("The prediction has no label name (no labels were given): "
                                 "assign a label instead")
            return False
        if obj.style_coanalysis.label == obj["style_label"]:
            cls.poll_message_set("The active object already carries its predicted label")
            return False
        return True

    def execute(self, context):
        obj = context.active_object
        name = obj["style_label"]
        settings = context.scene.style_coanalysis
        if name not in settings.label_names():
            bpy.ops.style.label_add(name=name)
        obj.style_coanalysis.label = name
        self.report({"INFO"}, f"'{obj.name}' labelled '{name}'")
        return {"FINISHED"}


class STYLE_OT_best_view_camera(bpy.types.Operator):
    """Place the camera 'Style Best View' at the active object's best view and make it the scene
    camera"""

    bl_idname = "style.best_view_camera"
    bl_label = "Camera to Best View"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        if obj is None or "style_best_view_matrix" not in obj:
            cls.poll_message_set("The active object has no best view: run Analyse Style")
            return False
        return True

    def execute(self, context):
        obj = context.active_object
        values = list(obj["style_best_view_matrix"])
        if len(values) != 16:
            self.report({"ERROR"}, f"'{obj.name}' has a malformed best view matrix")
            return {"CANCELLED"}
        cam = bpy.data.objects.get(CAMERA_NAME)
        if cam is None or cam.type != "CAMERA":
            cam = bpy.data.objects.new(CAMERA_NAME, bpy.data.cameras.new(CAMERA_NAME))
        if cam.name not in context.scene.objects:
            context.scene.collection.objects.link(cam)
        cam.matrix_world = Matrix([values[0:4], values[4:8], values[8:12], values[12:16]])
        context.scene.camera = cam
        self.report({"INFO"}, f"'{CAMERA_NAME}' at view {obj.get('style_best_view', '?')} "
                              f"of '{obj.name}'")
        return {"FINISHED"}


class STYLE_OT_toggle_highlight(bpy.types.Operator):
    """Show or hide the highlight material on the style regions of the selected objects"""

    bl_idname = "style.toggle_highlight"
    bl_label = "Toggle Style Highlight"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode")
            return False
        if not any(writeback.SLOTS_KEY in o.data for o in context.selected_objects
                   if o.type == "MESH"):
            cls.poll_message_set("No selected object carries style results")
            return False
        return True

    def execute(self, context):
        objs = [o for o in context.selected_objects
                if o.type == "MESH" and writeback.SLOTS_KEY in o.data]
        active = context.active_object
        ref = active if active in objs else objs[0]
        show = not bool(ref.data.get(writeback.SHOWN_KEY, True))
        done = set()
        for o in objs:
            if o.data.name not in done:
                writeback.set_highlight_shown(o, show)
                done.add(o.data.name)
        self.report({"INFO"}, f"Style highlight {'shown' if show else 'hidden'} on "
                              f"{len(done)} meshes")
        return {"FINISHED"}


class STYLE_OT_show_weights(bpy.types.Operator):
    """Paint view of the active object's style weights (Weight Paint mode on 'style_weight')"""

    bl_idname = "style.show_weights"
    bl_label = "Show Style Weights"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        if obj is None or obj.type != "MESH" or obj.vertex_groups.get(writeback.GROUP) is None:
            cls.poll_message_set("The active object has no style weights: run Analyse Style")
            return False
        return True

    def execute(self, context):
        obj = context.active_object
        obj.vertex_groups.active_index = obj.vertex_groups[writeback.GROUP].index
        if context.mode != "PAINT_WEIGHT":
            bpy.ops.object.mode_set(mode="WEIGHT_PAINT")
        return {"FINISHED"}


class STYLE_OT_clear_results(bpy.types.Operator):
    """Remove everything the last analysis and identification wrote (weights, highlight,
    clusters, properties); the meshes' own materials come back exactly"""

    bl_idname = "style.clear_results"
    bl_label = "Clear Style Results"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode")
            return False
        if not len(context.scene.style_coanalysis.clusters) and not any(
                _has_results(o) or writeback.has_identified(o) for o in context.scene.objects):
            cls.poll_message_set("There are no style results in this scene")
            return False
        return True

    def execute(self, context):
        n = writeback.clear_results(context.scene)
        m = writeback.clear_identified(context.scene)
        self.report({"INFO"}, f"Cleared style results from {n} objects"
                    + (f", identified styles from {m}" if m else ""))
        return {"FINISHED"}


CLASSES = (STYLE_OT_select_cluster, STYLE_OT_accept_prediction, STYLE_OT_best_view_camera,
           STYLE_OT_toggle_highlight, STYLE_OT_show_weights, STYLE_OT_clear_results)
