"""Sidebar tab "Style" of the 3D viewport, and the object's results in Object properties.

Drawing only: every change goes through an operator (undo, reports, poll messages) or a stored
property.
"""
import bpy

from ..operators.constraints import TRIPLET_HINT, triplet_from_context
from ..style_coanalysis.blender import decimate


class STYLE_UL_labels(bpy.types.UIList):
    """Labels with their colour, editable name and how many objects carry each."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index):
        count = sum(1 for o in context.scene.objects if o.style_coanalysis.label == item.name)
        row = layout.row(align=True)
        row.prop(item, "color", text="")
        row.prop(item, "name", text="", emboss=False)
        row.label(text=str(count))


class STYLE_UL_triplets(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index):
        names = item.names()
        if names is None:
            layout.label(text="(an object was deleted)", icon="ERROR")
        else:
            layout.label(text=f"{names[0]}  ~ {names[1]}  rather than {names[2]}")


class STYLE_UL_clusters(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index):
        row = layout.row()
        row.label(text=f"Cluster {item.cluster_id}")
        row.label(text=f"{item.size} shapes")
        row.label(text=item.label or "-")
        op = row.operator("style.select_cluster", text="", icon="RESTRICT_SELECT_OFF")
        op.cluster = item.cluster_id


class _StylePanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Style"


class VIEW3D_PT_style(_StylePanel, bpy.types.Panel):
    """The Analyse panel (class name kept: the install test looks for it)."""

    bl_label = "Analyse"

    def draw(self, context):
        s = context.scene.style_coanalysis
        col = self.layout.column()
        col.prop(s, "target", expand=True)
        if s.target == "COLLECTION":
            col.prop(s, "target_collection")
        col.prop(s, "renderer")
        col.prop(s, "up")
        row = col.row(align=True)
        row.prop(s, "auto_clusters")
        sub = row.row(align=True)
        sub.enabled = not s.auto_clusters
        sub.prop(s, "n_clusters")
        col.prop(s, "seed")
        col.operator("style.analyse", icon="VIEWZOOM")
        if s.last_report:
            col.label(text=s.last_report, icon="INFO")


class VIEW3D_PT_style_advanced(_StylePanel, bpy.types.Panel):
    bl_label = "Advanced"
    bl_parent_id = "VIEW3D_PT_style"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        s = context.scene.style_coanalysis
        col = self.layout.column()
        col.use_property_split = True
        for name in ("method", "n_representatives", "mu", "max_rounds"):
            col.prop(s, name)
        sub = col.column()
        sub.enabled = s.method == "paper"      # PSLF's: the default method does not read them
        for name in ("eta", "lam", "beta", "gamma"):
            sub.prop(s, name)


class VIEW3D_PT_style_labels(_StylePanel, bpy.types.Panel):
    bl_label = "Labels"

    def draw(self, context):
        s = context.scene.style_coanalysis
        row = self.layout.row()
        row.template_list("STYLE_UL_labels", "", s, "labels", s, "active_label_index", rows=3)
        col = row.column(align=True)
        col.operator("style.label_add", text="", icon="ADD")
        col.operator("style.label_remove", text="", icon="REMOVE")
        row = self.layout.row(align=True)
        row.operator("style.label_assign", icon="CHECKMARK")
        row.operator("style.label_clear", icon="X")


class VIEW3D_PT_style_triplets(_StylePanel, bpy.types.Panel):
    bl_label = "Triplets"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        s = context.scene.style_coanalysis
        col = self.layout.column(align=True)
        col.prop(s, "triplet_a")
        col.prop(s, "triplet_b", text="closer to B")
        col.prop(s, "triplet_c", text="than to C")
        row = col.row()
        ready = triplet_from_context(context) is not None
        row.enabled = ready
        row.operator("style.triplet_add", icon="ADD")
        if not ready:
            col.label(text=TRIPLET_HINT, icon="INFO")
        row = self.layout.row()
        row.template_list("STYLE_UL_triplets", "", s, "triplets", s, "active_triplet_index",
                          rows=3)
        col = row.column(align=True)
        col.operator("style.triplet_remove", text="", icon="REMOVE")
        col.operator("style.triplet_swap", text="", icon="ARROW_LEFTRIGHT")


def draw_object_results(layout, obj):
    """The object's own results (shared by the sidebar and the Object properties panel)."""
    if obj is None:
        layout.label(text="No active object")
        return
    if "style_cluster" not in obj:
        layout.label(text=f"'{obj.name}': no style results")
        return
    col = layout.column(align=True)
    col.label(text=f"Cluster {obj['style_cluster']}")
    label = obj.get("style_label") or "-"
    given = " (given)" if obj.get("style_label_given") else " (predicted)"
    col.label(text=f"Label: {label}{given if label != '-' else ''}")
    col.label(text=f"Confidence: {obj.get('style_confidence', 0.0):.2f}")
    col.label(text=f"Best view: {obj.get('style_best_view', '-')}")
    if obj.type == "MESH":
        col.label(text=f"Own label: {obj.style_coanalysis.label or '-'}")


class VIEW3D_PT_style_results(_StylePanel, bpy.types.Panel):
    bl_label = "Results"

    def draw(self, context):
        s = context.scene.style_coanalysis
        layout = self.layout
        layout.template_list("STYLE_UL_clusters", "", s, "clusters", s, "active_cluster_index",
                             rows=3)
        box = layout.box()
        draw_object_results(box, context.active_object)
        col = layout.column(align=True)
        col.operator("style.accept_prediction", icon="CHECKMARK")
        col.operator("style.best_view_camera", icon="CAMERA_DATA")
        row = col.row(align=True)
        row.operator("style.toggle_highlight", icon="MATERIAL")
        row.operator("style.show_weights", icon="MOD_VERTEX_WEIGHT")
        col.operator("style.clear_results", icon="TRASH")


class VIEW3D_PT_style_uses(_StylePanel, bpy.types.Panel):
    """Find shapes of the same style and what to label next (inside Results)."""
    bl_label = "Use the Style"
    bl_parent_id = "VIEW3D_PT_style_results"

    def draw(self, context):
        from ..operators.uses import IDENTIFIED_KEY, SIMILAR_KEY, SUGGESTED_KEY, read_list
        from ..style_coanalysis.blender.writeback import has_results
        layout = self.layout
        layout.operator("style.select_similar", icon="RESTRICT_SELECT_OFF")
        similar = read_list(context.scene, SIMILAR_KEY)
        if similar and has_results(context.scene.objects.get(similar["query"])):
            box = layout.box()
            box.label(text=f"Closest in style to {similar['query']}:")
            for k, (name, dist, cluster) in enumerate(similar["ranked"], start=1):
                box.label(text=f"{k}. {name}  ({dist:.3f}, cluster {cluster})")
        layout.operator("style.suggest_labels", icon="QUESTION")
        suggested = read_list(context.scene, SUGGESTED_KEY)
        if suggested and any(has_results(context.scene.objects.get(n)) for n, _ in suggested):
            box = layout.box()
            for k, (name, reason) in enumerate(suggested, start=1):
                box.label(text=f"{k}. {name}")
                box.label(text=f"    {reason}")
        layout.operator("style.identify_from_drawings", icon="FILE_IMAGE")
        identified = read_list(context.scene, IDENTIFIED_KEY)
        if identified:
            box = layout.box()
            for name, style, votes in identified:
                box.label(text=f"{name}: {style} ({votes} of the views)")


class VIEW3D_PT_style_decimate(_StylePanel, bpy.types.Panel):
    bl_label = "Decimate"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        s = context.scene.style_coanalysis
        col = self.layout.column()
        col.prop(s, "decimate_ratio")
        col.prop(s, "decimate_strength")
        col.prop(s, "decimate_hard")
        col.prop(s, "decimate_apply")
        for text, style, match in (("Style-Preserving", True, False), ("Plain", False, False),
                                   ("Plain, Same Count", False, True)):
            op = col.operator("style.decimate", text=text)
            op.ratio, op.strength, op.apply, op.hard = (s.decimate_ratio, s.decimate_strength,
                                                        s.decimate_apply, s.decimate_hard)
            op.style_preserving, op.match_style = style, match
        col.operator("style.decimate_remove", icon="X")
        obj = context.active_object
        if obj is not None and obj.type == "MESH":
            for name in (decimate.STYLE_MODIFIER, decimate.PLAIN_MODIFIER):
                if obj.modifiers.get(name):
                    col.label(text=f"{name}: {obj.modifiers[name].face_count} faces")


class OBJECT_PT_style_results(bpy.types.Panel):
    """The active object's style results in the Object properties editor."""

    bl_label = "Style Co-Analysis"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"
    bl_options = {"DEFAULT_CLOSED"}

    @classmethod
    def poll(cls, context):
        return context.object is not None and context.object.type == "MESH"

    def draw(self, context):
        draw_object_results(self.layout, context.object)
        self.layout.prop(context.object.style_coanalysis, "label")


CLASSES = (STYLE_UL_labels, STYLE_UL_triplets, STYLE_UL_clusters, VIEW3D_PT_style,
           VIEW3D_PT_style_advanced, VIEW3D_PT_style_labels, VIEW3D_PT_style_triplets,
           VIEW3D_PT_style_results, VIEW3D_PT_style_uses, VIEW3D_PT_style_decimate,
           OBJECT_PT_style_results)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
