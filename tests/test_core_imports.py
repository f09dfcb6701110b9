"""The analysis core must stay free of Blender (DESIGN.md, layer 3)."""
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BLENDER_IMPORT = re.compile(r"^\s*(import|from)\s+(bpy|bmesh|mathutils|bpy_extras)\b", re.M)


def test_no_core_module_imports_blender():
    offenders = [str(p.relative_to(ROOT)) for p in (ROOT / "style_coanalysis").rglob("*.py")
                 if "blender" not in p.relative_to(ROOT / "style_coanalysis").parts[:1]
                 and BLENDER_IMPORT.search(p.read_text())]
    assert offenders == []


def test_core_imports_in_a_python_without_bpy(tmp_path):
    """Import every core module with bpy made unimportable: proves the rule at run time too."""
    blocker = tmp_path / "bpy.py"
    blocker.write_text("raise ImportError('bpy is not available here')\n")
    mods = sorted(p.stem for p in (ROOT / "style_coanalysis").glob("*.py")
                  if p.stem not in ("__main__",))
    code = ("import importlib\n"
            f"for m in {mods!r}:\n"
            "    importlib.import_module('style_coanalysis.' + m if m != '__init__' else 'style_coanalysis')\n"
            "import sys; assert 'bpy' not in sys.modules or sys.modules['bpy'].__file__.startswith(%r)\n"
            "print('ok')\n" % str(tmp_path))
    res = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         env={"PYTHONPATH": f"{tmp_path}:{ROOT}", "PATH": "/usr/bin:/bin"})
    assert res.returncode == 0 and res.stdout.strip() == "ok", res.stderr[-2000:]


def test_cli_help_works_without_bpy(tmp_path):
    (tmp_path / "bpy.py").write_text("raise ImportError('no bpy')\n")
    res = subprocess.run([sys.executable, "-m", "style_coanalysis", "--help"], cwd=ROOT,
                         capture_output=True, text=True,
                         env={"PYTHONPATH": f"{tmp_path}:{ROOT}", "PATH": "/usr/bin:/bin"})
    assert res.returncode == 0 and "analyze" in res.stdout
