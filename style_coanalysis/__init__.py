"""Style co-analysis of 3D shapes from projected lines (after Yu et al.), pure Python core.

Importing this package never imports Blender: the `blender` subpackage is the only adapter and is
imported explicitly by the code that needs it.
"""
__version__ = "0.1.0"
