"""Style Co-Analysis: a Blender extension. This root is the extension package.

Registration only: the analysis lives in `style_coanalysis/` (pure Python), the Blender-facing
parts in `operators/` and `panels/`.
"""
from . import operators, panels


def register():
    operators.register()
    panels.register()


def unregister():
    panels.unregister()
    operators.unregister()
