"""A .blend of three cubes, one of them with a bad vertex: what the refusal tests feed the command."""
import subprocess
import sys


def write_blend_with_bad_vertex(path, bad_name: str, coordinate: str) -> None:
    """Save 'Good', `bad_name` and 'Other' (unit cubes) to `path`; vertex 0 of `bad_name` gets
    x = `coordinate` (Python source, e.g. "float('nan')" or "3.4e38"). Written by a fresh Python
    with bpy, so the test process's own Blender state is untouched."""
    code = f"""
import bpy, bmesh
bpy.ops.wm.read_factory_settings(use_empty=True)
for name in ("Good", {bad_name!r}, "Other"):
    me = bpy.data.meshes.new(name)
    bm = bmesh.new(); bmesh.ops.create_cube(bm, size=1.0); bm.to_mesh(me); bm.free()
    if name == {bad_name!r}:
        me.vertices[0].co = ({coordinate}, 0.0, 0.0)
    bpy.context.scene.collection.objects.link(bpy.data.objects.new(name, me))
bpy.ops.wm.save_as_mainfile(filepath={str(path)!r})
"""
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, timeout=120)
