"""The paper's camera rig (section 3): cameras every 30 degrees of azimuth, 30 degrees up.

Shapes are normalised into the unit sphere at the origin (see `meshes.normalise`), so one rig
serves every shape. Perspective pinhole cameras at `distance` from the origin with a field of
view that just holds the unit sphere (plus a margin), so nothing is ever cropped.
The 3x4 matrices map a point in the normalised frame to homogeneous pixels (x, y, w) in the
convention of `drawings.ShapeDrawings` ((0, 0) = top-left corner, y down).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Rig:
    n_views: int = 12
    elevation_deg: float = 30.0
    image_size: int = 200
    distance: float = 3.0
    margin: float = 1.05            # the unit sphere fills 1/margin of the half-width

    @property
    def fov(self) -> float:
        """Full field of view in radians (horizontal = vertical, square images)."""
        return 2.0 * math.asin(min(1.0, self.margin / self.distance))

    @property
    def focal_px(self) -> float:
        return (self.image_size / 2.0) / math.tan(self.fov / 2.0)

    def azimuths(self) -> np.ndarray:
        return np.arange(self.n_views) * (2.0 * math.pi / self.n_views)

    def locations(self) -> np.ndarray:
        """(V, 3) camera centres."""
        az = self.azimuths()
        el = math.radians(self.elevation_deg)
        return self.distance * np.stack(
            [np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.full_like(az, math.sin(el))], axis=1)

    def frames(self) -> np.ndarray:
        """(V, 3, 3) rows = camera right, up, forward (unit vectors, world frame, +Z up)."""
        out = []
        for loc in self.locations():
            fwd = -loc / np.linalg.norm(loc)
            right = np.cross(fwd, [0.0, 0.0, 1.0])
            right /= np.linalg.norm(right)
            up = np.cross(right, fwd)
            out.append(np.stack([right, up, fwd]))
        return np.asarray(out)

    def matrices(self) -> np.ndarray:
        """(V, 3, 4) projection matrices: [x, y, w] = P @ [X, Y, Z, 1]; pixel = (x/w, y/w)."""
        f = self.focal_px
        c = self.image_size / 2.0
        K = np.array([[f, 0.0, c], [0.0, -f, c], [0.0, 0.0, 1.0]])
        # camera coordinates: (right, up, forward); the -f flips y so that rows grow downwards
        mats = []
        for R, loc in zip(self.frames(), self.locations()):
            Rt = np.hstack([R, -(R @ loc)[:, None]])
            mats.append(K @ Rt)
        return np.asarray(mats)


def project(cameras: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Project (N, 3) points with (V, 3, 4) cameras: (V, N, 2) pixels and (V, N) depths."""
    hom = np.hstack([np.asarray(points, np.float64), np.ones((len(points), 1))])
    xyw = np.einsum("vij,nj->vni", cameras, hom)
    depth = xyw[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        pix = xyw[..., :2] / depth[..., None]
    return pix, depth
