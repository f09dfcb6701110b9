"""Blender operators: thin wrappers that read the scene, call the pipeline, write results back."""
import bpy

from . import analyse

_modules = (analyse,)


def register():
    for m in _modules:
        for cls in m.CLASSES:
            bpy.utils.register_class(cls)


def unregister():
    for m in reversed(_modules):
        for cls in reversed(m.CLASSES):
            bpy.utils.unregister_class(cls)
