"""What the renderers hand to the analysis for one shape: 12 ink images, the rig, the seeds.

This is the contract between the Blender adapter (which makes it) and the pure analysis (which
reads it). It is also what the per-shape cache stores, so it round-trips through `to_arrays`
and `from_arrays` (plain numpy arrays, an .npz file).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class ShapeDrawings:
    """Line drawings of one normalised shape.

    Pixel convention everywhere: (x, y) = (column, row) with (0, 0) the top-left corner of the
    image, so pixel [r, c] has its centre at (c + 0.5, r + 0.5) and the image centre is
    (size/2, size/2).
    """

    name: str
    images: np.ndarray           # (V, H, W) float32, 1 = ink, 0 = paper
    cameras: np.ndarray          # (V, 3, 4) float64 world(normalised) -> homogeneous pixel (x, y, w)
    seeds: np.ndarray            # (S, 3) float32 surface points, normalised frame
    seed_faces: np.ndarray       # (S,) int32 triangle each seed lies on
    seed_visible: np.ndarray     # (V, S) bool, seed seen by camera v (occlusion tested)
    seed_pixels: np.ndarray      # (V, S, 2) float32 projected (x, y)

    @property
    def n_views(self) -> int:
        return int(self.images.shape[0])

    def to_arrays(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__ if k != "name"} | {
            "name": np.array(self.name)}

    @classmethod
    def from_arrays(cls, arrays) -> "ShapeDrawings":
        """The fields' arrays; others are ignored (entries cached before 2026-12 also hold each
        vertex's visibility, which nothing read)."""
        data = {k: np.asarray(arrays[k]) for k in cls.__dataclass_fields__}
        data["name"] = str(data["name"])
        return cls(**data)
