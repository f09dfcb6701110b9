"""Per-shape on-disk cache of `ShapeDrawings`, so a second run renders nothing.

Key: sha256 of (the normalised mesh's geometry hash, `DrawingSettings.key()`, `CODE_VERSION`).
Each entry is one .npz holding the arrays plus the key and a checksum over every array, written
to a temporary file and moved into place with `os.replace` (readers never see half a file). An
entry that fails to load, has the wrong key, or whose checksum does not match is deleted and
reported as a miss: a damaged cache costs a re-render, never a wrong answer.
"""
from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path
from typing import Callable

import numpy as np

from .drawings import ShapeDrawings
from .meshes import Mesh

# Bump when the renderers, seeding or visibility change what they produce for the same input.
CODE_VERSION = "drawings-3"


def default_cache_dir() -> Path:
    """`$XDG_CACHE_HOME/style_coanalysis`, else `~/.cache/style_coanalysis`."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "style_coanalysis"


def cache_key(mesh: Mesh, settings, version: str = CODE_VERSION) -> str:
    """Hex key of a (normalised) mesh's drawings under `settings` (a `DrawingSettings`)."""
    payload = json.dumps({"mesh": mesh.content_hash(), "settings": settings.key(),
                          "version": version}, sort_keys=True, default=str)
    return hashlib.sha256(payload.encode()).hexdigest()


def arrays_checksum(arrays: dict) -> str:
    """sha256 over every array's name, dtype, shape and bytes (sorted by name)."""
    h = hashlib.sha256()
    for k in sorted(arrays):
        a = np.ascontiguousarray(arrays[k])
        h.update(k.encode())
        h.update(str(a.dtype).encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


class DrawingCache:
    """A folder of `<key>.npz` entries."""

    def __init__(self, root: str | os.PathLike | None = None):
        self.root = Path(root) if root is not None else default_cache_dir()

    def path(self, key: str) -> Path:
        return self.root / key[:2] / f"{key}.npz"

    def load(self, key: str) -> ShapeDrawings | None:
        """The entry for `key`, or None if absent or not trustworthy (then it is removed)."""
        path = self.path(key)
        if not path.exists():
            return None
        try:
            with np.load(path, allow_pickle=False) as data:
                arrays = {k: data[k] for k in data.files}
            stored_key = str(arrays.pop("_key"))
            stored_sum = str(arrays.pop("_checksum"))
            if stored_key != key or stored_sum != arrays_checksum(arrays):
                raise ValueError("key or checksum mismatch")
            return ShapeDrawings.from_arrays(arrays)
        except Exception:  # truncated zip, missing member, bad checksum: never trust it
            try:
                path.unlink()
            except OSError:
                pass
            return None

    def store(self, key: str, drawings: ShapeDrawings) -> Path:
        """Write atomically: a temporary file in the same folder, then `os.replace`."""
        path = self.path(key)
        path.parent.mkdir(parents=True, exist_ok=True)
        arrays = drawings.to_arrays()
        arrays = {k: np.asarray(v) for k, v in arrays.items()}
        fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=".npz", dir=path.parent)
        try:
            with os.fdopen(fd, "wb") as f:
                np.savez_compressed(f, _key=np.array(key), _checksum=np.array(arrays_checksum(arrays)),
                                    **arrays)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, path)
        except BaseException:
            try:
                os.unlink(tmp)
            except OSError:
                pass
            raise
        return path

    def get_or_compute(self, mesh: Mesh, settings, compute: Callable[[], ShapeDrawings],
                       version: str = CODE_VERSION) -> tuple[ShapeDrawings, bool]:
        """(drawings, was_cached). The cached entry takes `mesh.name`: equal geometry under
        another name shares the entry."""
        key = cache_key(mesh, settings, version)
        hit = self.load(key)
        if hit is not None:
            hit.name = mesh.name
            return hit, True
        drawings = compute()
        self.store(key, drawings)
        return drawings, False
