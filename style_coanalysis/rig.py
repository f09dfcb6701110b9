"""The paper's camera rig (section 3): cameras every 30 degrees of azimuth, 30 degrees up.

Shapes are normalised into the unit sphere at the origin (see `meshes.normalise`), so one rig
serves every shape. Perspective pinhole cameras at `distance` from the origin with a field of
view that just holds the unit sphere (plus a margin), so nothing is ever cropped.
The 3x4 matrices map a point in the normalised frame to homogeneous pixels (x, y, w) in the
convention of `drawings.ShapeDrawings` ((0, 0) = top-left corner, y down).

Quarter turns: when the views fall on the axes every quarter turn (12 views: 0, 3, 6, 9), the
renderers draw view `v` with the first quarter's camera `camera_of(v)` and the shape turned
by `quarter_of(v)` quarter turns into it (`into_quarter`), rather than with a camera of its own.
A quarter turn only swaps and negates coordinates, so it is exact in floating point: a shape
turned by a quarter about its up axis hands every renderer the same numbers for view v + 3 as
the original did for view v, and is drawn exactly as the original with its views shifted
(a camera of its own saw the geometry through its own rounded matrix, and a few pixels and
seeds moved, and with them the partition: issue 11's turned route). `matrices()` describes
each view in the normalised frame (the same projection up to rounding); `project_views` is the
one the renderers use.
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

    @property
    def quarters(self) -> int:
        """How many quarter turns of the shape the views take: 4 when they fall on the axes
        every quarter turn (`n_views` a multiple of 4), else 1 (a camera for every view)."""
        return 4 if self.n_views % 4 == 0 else 1

    @property
    def n_cameras(self) -> int:
        """The cameras the renderers place: the first quarter's views."""
        return self.n_views // self.quarters

    def camera_of(self, view: int) -> int:
        return view % self.n_cameras

    def quarter_of(self, view: int) -> int:
        return view // self.n_cameras

    def azimuths(self) -> np.ndarray:
        return np.arange(self.n_views) * (2.0 * math.pi / self.n_views)

    def camera_locations(self) -> np.ndarray:
        """(C, 3) centres of the cameras the renderers place."""
        az = self.azimuths()[:self.n_cameras]
        el = math.radians(self.elevation_deg)
        return self.distance * np.stack(
            [np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.full_like(az, math.sin(el))], axis=1)

    def camera_frames(self) -> np.ndarray:
        """(C, 3, 3) rows = camera right, up, forward (unit vectors, +Z up) of those cameras."""
        out = []
        for loc in self.camera_locations():
            fwd = -loc / np.linalg.norm(loc)
            right = np.cross(fwd, [0.0, 0.0, 1.0])
            right /= np.linalg.norm(right)
            up = np.cross(right, fwd)
            out.append(np.stack([right, up, fwd]))
        return np.asarray(out)

    def camera_matrices(self) -> np.ndarray:
        """(C, 3, 4) projection matrices of those cameras: [x, y, w] = P @ [X, Y, Z, 1]; pixel =
        (x/w, y/w)."""
        f = self.focal_px
        c = self.image_size / 2.0
        K = np.array([[f, 0.0, c], [0.0, -f, c], [0.0, 0.0, 1.0]])
        # camera coordinates: (right, up, forward); the -f flips y so that rows grow downwards
        mats = []
        for R, loc in zip(self.camera_frames(), self.camera_locations()):
            Rt = np.hstack([R, -(R @ loc)[:, None]])
            mats.append(K @ Rt)
        return np.asarray(mats)

    def into_quarter(self, points: np.ndarray, quarter: int) -> np.ndarray:
        """`points` (N, 3) turned into the frame of the views of `quarter`, where their cameras
        (`camera_of`) see them as those views do: exact (coordinates swapped and negated)."""
        return quarter_turn(points, -quarter)

    def project_views(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`project` into every view as the renderers draw it (its camera, the points turned
        into its frame): (V, N, 2) pixels and (V, N) depths."""
        mats = self.camera_matrices()
        out = [project(mats[None, self.camera_of(v)],
                       self.into_quarter(points, self.quarter_of(v))) for v in range(self.n_views)]
        return np.concatenate([o[0] for o in out]), np.concatenate([o[1] for o in out])

    def locations(self) -> np.ndarray:
        """(V, 3) every view's camera centre in the normalised frame."""
        locs = self.camera_locations()
        return np.stack([quarter_turn(locs[self.camera_of(v)][None], self.quarter_of(v))[0]
                         for v in range(self.n_views)])

    def frames(self) -> np.ndarray:
        """(V, 3, 3) every view's camera right, up, forward in the normalised frame."""
        frames = self.camera_frames()
        return np.stack([quarter_turn(frames[self.camera_of(v)], self.quarter_of(v))
                         for v in range(self.n_views)])

    def matrices(self) -> np.ndarray:
        """(V, 3, 4) every view's projection of the normalised frame: its camera's matrix
        with the quarter turn folded into the columns (exact)."""
        mats = self.camera_matrices()
        out = []
        for v in range(self.n_views):
            m = mats[self.camera_of(v)].copy()
            m[:, :3] = quarter_turn(m[:, :3], self.quarter_of(v))
            out.append(m)
        return np.asarray(out)


def quarter_turn(points: np.ndarray, quarters: int) -> np.ndarray:
    """(N, 3) points turned by `quarters` quarter turns counter-clockwise about +Z (negative:
    clockwise). Exact: it swaps and negates x and y."""
    p = np.asarray(points)
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    q = quarters % 4
    if q == 0:
        return p.copy()
    turned = {1: (-y, x), 2: (-x, -y), 3: (y, -x)}[q]
    return np.stack([turned[0], turned[1], z], axis=-1)


def project(cameras: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Project (N, 3) points with (V, 3, 4) cameras: (V, N, 2) pixels and (V, N) depths."""
    hom = np.hstack([np.asarray(points, np.float64), np.ones((len(points), 1))])
    xyw = np.einsum("vij,nj->vni", cameras, hom)
    depth = xyw[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        pix = xyw[..., :2] / depth[..., None]
    return pix, depth
