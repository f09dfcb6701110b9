"""Build and validate the extension zips, one per platform, with Blender's own tool.

Why a script: the manifest's `wheels` list must name the wheel files of every platform, and those
are downloaded at build time (never committed). So the tracked files are staged into
build/stage, the wheels for each platform are fetched into a cache and copied beside them, the
staged manifest gets the wheel list, and `blender_ext.py build --split-platforms` makes one zip
per platform, each then checked by `blender_ext.py validate` with Blender's tag list.
numpy is never bundled: Blender ships it, and a second copy breaks Blender and other add-ons.

    python tools/build_dist.py [--platforms linux-x64 ...] [--out dist]
"""
from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# pip's --platform tags per Blender platform: several, newest last, so any published wheel fits
PIP_PLATFORMS = {
    "linux-x64": ["manylinux2014_x86_64", "manylinux_2_17_x86_64", "manylinux_2_28_x86_64"],
    "windows-x64": ["win_amd64"],
    "macos-arm64": ["macosx_11_0_arm64", "macosx_12_0_arm64", "macosx_14_0_arm64"],
    "macos-x64": ["macosx_10_9_x86_64", "macosx_10_13_x86_64", "macosx_10_14_x86_64",
                  "macosx_10_15_x86_64", "macosx_12_0_x86_64", "macosx_13_0_x86_64",
                  "macosx_14_0_x86_64"],
}
NEVER_BUNDLE = ("numpy",)


def wheel_cache() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache")
    return Path(base) / "style_coanalysis" / "wheels"


def blender_cli() -> tuple[Path, Path]:
    """Blender's extension command line and tag list, shipped inside the bpy wheel."""
    import importlib.util
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        sys.exit("error: the bpy module is not installed in this Python (run 'make setup')")
    scripts = next(Path(p) for p in spec.submodule_search_locations) / "5.0" / "scripts"
    return (scripts / "addons_core/bl_pkg/cli/blender_ext.py",
            scripts / "modules/_bpy_internal/extensions/tags.py")


def runtime_requirements() -> list[str]:
    """Pinned runtime packages from requirements.txt, numpy excluded."""
    reqs = []
    for line in (ROOT / "requirements.txt").read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if line and not line.lower().startswith(NEVER_BUNDLE):
            reqs.append(line)
    return reqs


def download_wheels(platform: str) -> list[Path]:
    """Fetch (once, cached) the binary wheels of the runtime packages for a platform, numpy dropped."""
    dest = wheel_cache() / platform
    dest.mkdir(parents=True, exist_ok=True)
    cmd = [sys.executable, "-m", "pip", "download", "--quiet", "--only-binary=:all:",
           "--python-version", "3.11", "--implementation", "cp", "--abi", "cp311", "--abi", "none",
           "--abi", "abi3", "-d", str(dest)]
    for tag in PIP_PLATFORMS[platform]:
        cmd += ["--platform", tag]
    cmd += runtime_requirements() + ["numpy==1.26.4"]  # numpy only to satisfy the resolver
    subprocess.run(cmd, check=True)
    wheels = sorted(p for p in dest.glob("*.whl") if not p.name.lower().startswith(NEVER_BUNDLE))
    return wheels


def stage_sources(stage: Path) -> None:
    """Copy the tracked files (what a clean clone has) into the staging folder."""
    if stage.exists():
        shutil.rmtree(stage)
    files = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, check=True,
                           capture_output=True).stdout.decode().split("\0")
    for rel in filter(None, files):
        src = ROOT / rel
        if src.is_file():
            (stage / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, stage / rel)


def write_manifest(stage: Path, wheel_names: list[str], platforms: list[str]) -> None:
    """Fill the staged manifest's wheels and platforms lists (the tracked one is left alone)."""
    text = (stage / "blender_manifest.toml").read_text()
    wheels = ",\n".join(f'  "./wheels/{n}"' for n in wheel_names)
    text = re.sub(r"^wheels = \[.*?\]", f"wheels = [\n{wheels}\n]", text, flags=re.S | re.M)
    plats = ", ".join(f'"{p}"' for p in platforms)
    text = text.replace("\n[permissions]", f"\nplatforms = [{plats}]\n\n[permissions]", 1)
    (stage / "blender_manifest.toml").write_text(text)


def build(platforms: list[str], out: Path) -> list[Path]:
    cli, tags = blender_cli()
    stage = ROOT / "build" / "stage"
    stage_sources(stage)
    (stage / "wheels").mkdir()
    names = []
    for platform in platforms:
        print(f"wheels for {platform} ...", flush=True)
        for whl in download_wheels(platform):
            if not (stage / "wheels" / whl.name).exists():
                shutil.copy2(whl, stage / "wheels" / whl.name)
                names.append(whl.name)
    write_manifest(stage, sorted(names), platforms)
    out.mkdir(parents=True, exist_ok=True)
    for old in out.glob("style_coanalysis-*.zip"):
        old.unlink()
    subprocess.run([sys.executable, str(cli), "build", "--source-dir", str(stage), "--output-dir",
                    str(out), "--split-platforms", "--valid-tags", str(tags)], check=True)
    zips = sorted(out.glob("style_coanalysis-*.zip"))
    for z in zips:
        subprocess.run([sys.executable, str(cli), "validate", "--valid-tags", str(tags), str(z)],
                       check=True)
        with zipfile.ZipFile(z) as zf:
            bad = [n for n in zf.namelist() if n.split("/")[-1].lower().startswith(NEVER_BUNDLE)
                   or n.startswith(("tests/", "bench/", "tools/", ".venv/"))]
        if bad:
            sys.exit(f"error: {z.name} contains files it must not ship: {bad[:5]}")
        print(f"{z.name}: {z.stat().st_size / 2**20:.1f} MiB, validated")
    return zips


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--platforms", nargs="+", default=list(PIP_PLATFORMS), choices=list(PIP_PLATFORMS))
    ap.add_argument("--out", default=str(ROOT / "dist"))
    args = ap.parse_args()
    build(args.platforms, Path(args.out))


if __name__ == "__main__":
    main()
