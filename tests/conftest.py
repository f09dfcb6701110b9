"""Shared fixtures. `ext`: the repository root registered as a Blender extension package.

The root is imported under another package name, as Blender does when it installs it
(bl_ext.<repo>.<id>), so relative imports are exercised; the test that installs the real zip
is tests/test_extension.py.
"""
import importlib.util
import os
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
PKG = "style_coanalysis_ext"


def load_extension():
    """The repo root imported as a package named PKG (once per process)."""
    if PKG not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            PKG, ROOT / "__init__.py", submodule_search_locations=[str(ROOT)])
        module = importlib.util.module_from_spec(spec)
        sys.modules[PKG] = module
        spec.loader.exec_module(module)
    return sys.modules[PKG]


@pytest.fixture(scope="session", autouse=True)
def user_cache(tmp_path_factory):
    """The session's own user cache (XDG_CACHE_HOME, inherited by the commands the tests start),
    so the suite never reads or writes the machine's: a test's result cannot come from an entry
    an earlier version left there."""
    before = os.environ.get("XDG_CACHE_HOME")
    os.environ["XDG_CACHE_HOME"] = str(tmp_path_factory.mktemp("user_cache"))
    yield Path(os.environ["XDG_CACHE_HOME"])
    if before is None:
        del os.environ["XDG_CACHE_HOME"]
    else:
        os.environ["XDG_CACHE_HOME"] = before


@pytest.fixture(scope="module")
def ext():
    pytest.importorskip("bpy")
    module = load_extension()
    module.register()
    yield module
    module.unregister()


DAMAGES = ("truncate", "flip", "swap")


def damage_entry(path: Path, how: str, array: str, other: Path) -> None:
    """Spoil a cache entry (.npz) the ways a disk or a person can: cut short, one value of
    `array` changed inside a valid zip (only the checksum can tell), or another entry's valid
    file (`other`) put in its place."""
    if how == "truncate":
        raw = path.read_bytes()
        path.write_bytes(raw[: len(raw) // 2])
    elif how == "flip":
        with np.load(path) as z:
            arrays = {k: z[k] for k in z.files}
        arrays[array] = arrays[array].copy()
        arrays[array].flat[np.argmax(arrays[array])] += 0.5
        np.savez(path, **arrays)
    else:
        path.write_bytes(other.read_bytes())
