"""Whole files or none: every file the package writes goes through here.

A file is written to a temporary name in its own folder and moved into place with `os.replace`,
so a reader (a second run, another worker, the user) never sees half a file, and an error or a
Ctrl-C leaves no temporary behind. An .npz is built in memory first: numpy's writer does not
close its zip on an exception, and a zip left open on a closed file reports a traceback when it
is collected, after the run has already said "interrupted".
"""
from __future__ import annotations

import io
import os
import tempfile
from pathlib import Path

import numpy as np


def write_bytes(path, data: bytes, fsync: bool = False) -> Path:
    """`data` as the whole of `path`; `fsync` when a crash must not leave an empty file."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            if fsync:
                fh.flush()
                os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    return path


def write_text(path, text: str) -> Path:
    return write_bytes(path, text.encode("utf-8"))


def npz_bytes(arrays: dict, compress: bool = True) -> bytes:
    """The .npz file of `arrays` (names to arrays), as bytes."""
    buf = io.BytesIO()
    (np.savez_compressed if compress else np.savez)(buf, **arrays)
    return buf.getvalue()
