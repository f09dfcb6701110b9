"""The style space of the last analysis, kept in the .blend (scene custom property).

Why in the scene: the Style panel's later uses (Select Similar Style, Suggest Shapes to Label)
run long after the analysis, after saving and reloading, without re-drawing anything. A JSON
string is the simplest ID property that survives save, reload and undo unchanged.
"""
from __future__ import annotations

import json

import numpy as np

from ..similarity import StyleSpace

KEY = "style_space"


def write_scene(scene, space: StyleSpace | None) -> None:
    if space is None:
        return
    d = space.to_dict()
    scene[KEY] = json.dumps({k: np.asarray(v).tolist() for k, v in d.items()})


def read_scene(scene) -> StyleSpace | None:
    """The stored space, or None when there is none (or it cannot be read)."""
    text = scene.get(KEY)
    if not isinstance(text, str):
        return None
    try:
        d = json.loads(text)
        return StyleSpace.from_dict({k: np.asarray(v) for k, v in d.items()})
    except (ValueError, KeyError, TypeError):
        return None
