"""The extension as users get it: built by Blender's tool, validated, installed, registered.

The install runs in a fresh Python process with HOME and BLENDER_USER_RESOURCES pointed at a
temporary folder, so the developer's own Blender configuration is never touched and the
wheels Blender unpacks do not leak into this test process.
"""
import json
import os
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
import build_dist  # noqa: E402

pytestmark = pytest.mark.blender


@pytest.fixture(scope="module")
def linux_zip(tmp_path_factory):
    out = tmp_path_factory.mktemp("dist")
    zips = build_dist.build(["linux-x64"], out)
    assert len(zips) == 1 and zips[0].name.endswith("linux_x64.zip")
    return zips[0]


def test_zip_ships_the_extension_and_its_wheels_but_no_numpy_or_tests(linux_zip):
    names = zipfile.ZipFile(linux_zip).namelist()
    assert "blender_manifest.toml" in names and "__init__.py" in names
    assert any(n.startswith("style_coanalysis/") for n in names)
    assert "style_coanalysis/vocabularies.npz" in names         # the default's words, not made
    wheels = [n for n in names if n.startswith("wheels/")]
    for pkg in ("scipy", "scikit_learn", "scikit_image"):
        assert any(n.split("/")[1].startswith(pkg) for n in wheels), pkg
    assert not any(n.split("/")[1].startswith("numpy") for n in wheels)
    assert not any(n.startswith(("tests/", "bench/", "tools/", "style_coanalysis/evaluation/"))
                   for n in names)


def test_validator_rejects_a_bad_tag(tmp_path):
    """The validation step is real: an unknown tag is refused with Blender's tag list."""
    cli, tags = build_dist.blender_cli()
    src = tmp_path / "ext"
    src.mkdir()
    manifest = (ROOT / "blender_manifest.toml").read_text().replace('"Pipeline"', '"Not A Tag"')
    (src / "blender_manifest.toml").write_text(manifest)
    (src / "__init__.py").write_text("def register(): pass\ndef unregister(): pass\n")
    res = subprocess.run([sys.executable, str(cli), "validate", "--valid-tags", str(tags), str(src)],
                         capture_output=True, text=True)
    assert res.returncode != 0
    assert "Not A Tag" in (res.stdout + res.stderr)


INSTALL = textwrap.dedent("""
    import json, sys
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    res = bpy.ops.extensions.package_install_files(
        filepath=sys.argv[1], repo="user_default", enable_on_install=True)
    module = "bl_ext.user_default.style_coanalysis"
    import addon_utils
    state = {"install": sorted(res)}
    state["enabled"] = module in {m for m in bpy.context.preferences.addons.keys()}
    state["panel"] = hasattr(bpy.types, "VIEW3D_PT_style")
    state["operator"] = hasattr(bpy.types, "STYLE_OT_analyse")
    import io, os, contextlib
    ext = sys.modules[module]
    state["cli_registered"] = ext._cli_handle is not None
    err = io.StringIO()
    with contextlib.redirect_stderr(err):   # the handler Blender's `-c style_coanalysis` calls
        state["cli_rc"] = ext.run_cli(["analyze", "/nonexistent/in.blend", "--out", sys.argv[2]])
    state["cli_err"] = err.getvalue()
    # a small real run through the installed package: `sample` then `analyze` a folder, both of
    # which start from an empty scene; that must not disable the extension (and drop its wheels)
    work = os.path.join(sys.argv[2], "run")
    with contextlib.redirect_stderr(io.StringIO()) as run_err:
        state["sample_rc"] = ext.run_cli(["sample", "--out", work, "--size", "3", "--seed", "1"])
        state["analyze_rc"] = ext.run_cli([
            "analyze", os.path.join(work, "meshes"), "--out", os.path.join(work, "out"),
            "--renderer", "lineart", "--jobs", "1", "--rounds", "1", "--clusters", "2",
            "--cache", os.path.join(work, "cache")])
    state["run_err"] = run_err.getvalue()[-2000:]
    state["enabled_after_run"] = module in {m for m in bpy.context.preferences.addons.keys()}
    state["out"] = sorted(os.listdir(os.path.join(work, "out"))) if state["analyze_rc"] == 0 else []
    local = os.path.join(bpy.utils.user_resource("EXTENSIONS"), ".local")
    state["wheels"] = sorted(p for p in ("sklearn", "scipy", "skimage") if any(
        os.path.isfile(os.path.join(r, p, "__init__.py")) for r, _, _ in os.walk(local)))
    state["local_in_home"] = local.startswith(sys.argv[2])
    bpy.ops.preferences.addon_disable(module=module)
    state["panel_after"] = hasattr(bpy.types, "VIEW3D_PT_style")
    state["operator_after"] = hasattr(bpy.types, "STYLE_OT_analyse")
    state["enabled_after"] = module in {m for m in bpy.context.preferences.addons.keys()}
    print("STATE" + json.dumps(state))
""")


def test_installs_registers_and_unregisters_in_blender(linux_zip, tmp_path):
    env = dict(os.environ, HOME=str(tmp_path), BLENDER_USER_RESOURCES=str(tmp_path / "blender"))
    res = subprocess.run([sys.executable, "-c", INSTALL, str(linux_zip), str(tmp_path)], env=env,
                         capture_output=True, text=True, timeout=300)
    lines = [l for l in res.stdout.splitlines() if l.startswith("STATE")]
    assert res.returncode == 0 and lines, res.stdout[-2000:] + res.stderr[-2000:]
    state = json.loads(lines[-1][5:])
    assert state["install"] == ["FINISHED"]
    assert state["enabled"] and state["panel"] and state["operator"]
    # the command line registered with Blender runs from the installed package (relative imports)
    assert state["cli_registered"]
    assert state["cli_rc"] == 2 and "/nonexistent/in.blend" in state["cli_err"]
    assert state["sample_rc"] == 0 and state["analyze_rc"] == 0, state["run_err"]
    assert state["enabled_after_run"]
    assert {"result.blend", "report.json", "report.html", "images"} <= set(state["out"])
    assert not state["panel_after"] and not state["operator_after"] and not state["enabled_after"]
    assert "Traceback" not in res.stderr, res.stderr[-2000:]
    # installed under the temporary user folder, not the developer's
    assert any((tmp_path / "blender").rglob("blender_manifest.toml"))
    # the bundled wheels were unpacked into the temporary extensions' own site-packages
    assert state["wheels"] == ["scipy", "skimage", "sklearn"] and state["local_in_home"]
