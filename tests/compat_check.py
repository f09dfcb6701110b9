"""`make test-compat`: the built extension zip in an older Blender (bpy 4.2 LTS, 4.5 LTS).

Run with the Python of a venv holding that bpy: `python tests/compat_check.py ZIP WORKDIR
[RENDERER ...]`. In a fresh process with HOME and BLENDER_USER_RESOURCES under WORKDIR (the
developer's configuration is never touched) it installs and enables the zip as a user would,
checks the panel, the operator and the command line are registered, runs one small headless
analysis per renderer through Blender's own command-line handler (the installed package, its
bundled wheels), checks the result, and disables the extension again. Prints one JSON line
'COMPAT {...}' and exits 0 only when everything held.
"""
import json
import os
import subprocess
import sys

CHILD = r"""
import contextlib, io, json, os, sys
import bpy
zip_path, work = sys.argv[1], sys.argv[2]
renderers = sys.argv[3:]
state = {"blender": bpy.app.version_string, "version": list(bpy.app.version)}
bpy.ops.wm.read_factory_settings(use_empty=True)
res = bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default",
                                               enable_on_install=True)
module = "bl_ext.user_default.style_coanalysis"
state["install"] = sorted(res)
state["enabled"] = module in bpy.context.preferences.addons.keys()
state["panel"] = hasattr(bpy.types, "VIEW3D_PT_style")
state["operator"] = hasattr(bpy.types, "STYLE_OT_analyse")
ext = sys.modules[module]
state["cli_registered"] = ext._cli_handle is not None
err = io.StringIO()
with contextlib.redirect_stderr(err):
    state["sample_rc"] = ext.run_cli(["sample", "--out", os.path.join(work, "sample"),
                                      "--size", "8", "--seed", "1"])
state["analyses"] = {}
for r in renderers:
    out = os.path.join(work, "out_" + r)
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = ext.run_cli(["analyze", os.path.join(work, "sample", "sample.blend"), "--out", out,
                          "--renderer", r, "--jobs", "1", "--rounds", "2",
                          "--cache", os.path.join(work, "cache")])
    report = {}
    if rc == 0:
        with open(os.path.join(out, "report.json")) as fh:
            report = json.load(fh)
    state["analyses"][r] = {"rc": rc, "shapes": len(report.get("shapes", [])),
                            "files": sorted(os.listdir(out)) if os.path.isdir(out) else [],
                            "stderr_tail": err.getvalue()[-1500:]}
bpy.ops.preferences.addon_disable(module=module)
state["disabled"] = module not in bpy.context.preferences.addons.keys()
print("STATE" + json.dumps(state))
"""


def main(argv):
    zip_path, work = os.path.abspath(argv[0]), os.path.abspath(argv[1])
    renderers = argv[2:] or ["freestyle"]
    os.makedirs(work, exist_ok=True)
    env = dict(os.environ, HOME=work, BLENDER_USER_RESOURCES=os.path.join(work, "blender"))
    res = subprocess.run([sys.executable, "-c", CHILD, zip_path, work, *renderers], env=env,
                         capture_output=True, text=True, timeout=1800)
    lines = [ln for ln in res.stdout.splitlines() if ln.startswith("STATE")]
    if res.returncode != 0 or not lines:
        print(res.stdout[-3000:], res.stderr[-3000:], file=sys.stderr)
        print("COMPAT " + json.dumps({"ok": False, "error": "the Blender process failed"}))
        return 1
    state = json.loads(lines[-1][5:])
    checks = {
        "installed": state["install"] == ["FINISHED"] and state["enabled"],
        "registered": state["panel"] and state["operator"] and state["cli_registered"],
        "sample": state["sample_rc"] == 0,
        "disabled": state["disabled"],
    }
    for r, a in state["analyses"].items():
        if r == "lineart" and tuple(state["version"]) < (4, 3, 0):
            # no Grease Pencil v3 before 4.3: refused up front, by name, not a crash
            checks["lineart refused before 4.3"] = (
                a["rc"] == 2 and "Line Art renderer needs Blender 4.3" in a["stderr_tail"]
                and "] render" not in a["stderr_tail"])
            continue
        checks[f"analyse ({r})"] = (a["rc"] == 0 and a["shapes"] == 8 and
                                    {"result.blend", "report.json", "report.html"} <= set(a["files"]))
    state["checks"] = checks
    state["ok"] = all(checks.values())
    print("COMPAT " + json.dumps(state))
    return 0 if state["ok"] else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
