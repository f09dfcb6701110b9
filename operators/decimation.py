"""Decimate the selected meshes, style-preserving or plain, and report what was reached."""
import bpy
from bpy.props import BoolProperty, FloatProperty

from ..style_coanalysis.blender import decimate, writeback


def _targets(context):
    return [o for o in context.selected_objects if o.type == "MESH"]


def describe(res: dict) -> str:
    kind = (("style-preserving" if res["hard"] else "style-preferring")
            if res["style_preserving"] else "plain")
    return (f"'{res['object']}' {kind}: {res['triangles']} of {res['triangles_before']} triangles "
            f"(asked {res['requested_triangles']}), style regions "
            f"{res['style_triangles']} of {res['style_triangles_before']}")


class STYLE_OT_decimate(bpy.types.Operator):
    """Decimate the selected meshes with Blender's Decimate modifier; style-preserving keeps the
    triangles of the style regions"""

    bl_idname = "style.decimate"
    bl_label = "Decimate"
    bl_options = {"REGISTER", "UNDO"}

    ratio: FloatProperty(name="Ratio", min=0.0, max=1.0, default=0.3, subtype="FACTOR",
                         description="Fraction of triangles to keep (0.3: 70% reduction)")
    strength: FloatProperty(name="Strength", min=0.0, max=1000.0, soft_max=10.0, default=1.0,
                            description="Vertex group factor: how much style weights raise the "
                                        "collapse cost")
    style_preserving: BoolProperty(name="Style-Preserving", default=True)
    match_style: BoolProperty(
        name="Match Style-Preserving Count", default=False,
        description="Plain only: tune the ratio to reach the triangle count the style-preserving "
                    "modifier reaches (fair comparison)")
    hard: BoolProperty(name="Protect Fully", default=True,
                       description="Never collapse vertices of style weight 1 (the ratio may be "
                                   "out of reach); off: collapse style regions last")
    apply: BoolProperty(name="Apply", default=False,
                        description="Apply the modifier to the mesh")

    @classmethod
    def poll(cls, context):
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode to decimate")
            return False
        if not _targets(context):
            cls.poll_message_set("Select the mesh objects to decimate")
            return False
        return True

    def execute(self, context):
        needs_group = self.style_preserving or self.match_style
        done = 0
        for obj in _targets(context):
            if needs_group and obj.vertex_groups.get(writeback.GROUP) is None:
                self.report({"WARNING"}, f"'{obj.name}' has no style weights (run Analyse "
                                         "Style): skipped")
                continue
            try:
                if self.style_preserving:
                    res = decimate.add_decimate(obj, self.ratio, self.strength, True, self.apply,
                                                hard=self.hard)
                elif self.match_style:
                    ref = decimate.add_decimate(obj, self.ratio, self.strength, True, False,
                                                hard=self.hard)
                    res = decimate.match_plain_to(obj, ref["triangles"], apply=self.apply)
                else:
                    res = decimate.add_decimate(obj, self.ratio, 0.0, False, self.apply)
            except (ValueError, RuntimeError) as exc:
                self.report({"ERROR"}, f"'{obj.name}': {exc}")
                continue
            self.report({"INFO"}, describe(res))
            done += 1
        return {"FINISHED"} if done else {"CANCELLED"}


class STYLE_OT_decimate_remove(bpy.types.Operator):
    """Remove the decimate modifiers this add-on put on the selected meshes"""

    bl_idname = "style.decimate_remove"
    bl_label = "Remove Decimation"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        names = (decimate.STYLE_MODIFIER, decimate.PLAIN_MODIFIER)
        if not any(m.name in names for o in _targets(context) for m in o.modifiers):
            cls.poll_message_set("No selected mesh has a style or plain Decimate modifier")
            return False
        return True

    def execute(self, context):
        for obj in _targets(context):
            decimate.remove_decimate(obj)
        return {"FINISHED"}


CLASSES = (STYLE_OT_decimate, STYLE_OT_decimate_remove)
