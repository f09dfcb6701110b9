"""The Analyse operator (placeholder until the panel issue lands)."""
import bpy


class STYLE_OT_analyse(bpy.types.Operator):
    """Analyse the selected meshes for shared decorative style"""

    bl_idname = "style.analyse"
    bl_label = "Analyse Style"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        if not any(o.type == "MESH" for o in context.selected_objects):
            cls.poll_message_set("Select at least two mesh objects")
            return False
        return True

    def execute(self, context):
        self.report({"ERROR"}, "Analysis is not available yet")
        return {"CANCELLED"}


CLASSES = (STYLE_OT_analyse,)
