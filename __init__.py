"""Style Co-Analysis: a Blender extension. This root is the extension package.

Registration only: the analysis lives in `style_coanalysis/` (pure Python), the Blender-facing
parts in `operators/` and `panels/`. The headless command is also registered with Blender's own
command line: `blender -b -c style_coanalysis analyze INPUT --out DIR`.
"""
import bpy

from . import operators, panels

CLI_COMMAND = "style_coanalysis"
_cli_handle = None


def run_cli(argv):
    """Blender's `-c style_coanalysis ...` handler: the same parser as `python -m style_coanalysis`."""
    from .style_coanalysis.cli import main
    return main(list(argv))


def register():
    global _cli_handle
    operators.register()
    panels.register()
    _cli_handle = bpy.utils.register_cli_command(CLI_COMMAND, run_cli)


def unregister():
    global _cli_handle
    if _cli_handle is not None:
        bpy.utils.unregister_cli_command(_cli_handle)
        _cli_handle = None
    panels.unregister()
    operators.unregister()
