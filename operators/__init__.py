"""Blender operators: thin wrappers that read the scene, call the pipeline, write results back.

Registration also owns the stored properties (`style_coanalysis.blender.properties`): they are
registered first because the operators and panels read them, and unregistered last.
"""
import bpy

from ..style_coanalysis.blender import properties
from . import analyse, constraints, decimation, results, uses

_modules = (analyse, constraints, results, uses, decimation)


def register():
    properties.register()
    for m in _modules:
        for cls in m.CLASSES:
            bpy.utils.register_class(cls)


def unregister():
    for m in reversed(_modules):
        for cls in reversed(m.CLASSES):
            bpy.utils.unregister_class(cls)
    properties.unregister()
