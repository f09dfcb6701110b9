"""Sidebar panels of the 3D viewport, tab "Style"."""
import bpy


class VIEW3D_PT_style(bpy.types.Panel):
    bl_label = "Style Co-Analysis"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Style"

    def draw(self, context):
        self.layout.operator("style.analyse")


CLASSES = (VIEW3D_PT_style,)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
