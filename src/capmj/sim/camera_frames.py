"""What a camera rig renders: one perspective view (:class:`CameraFrame`), the top-down
:class:`Heightmap`, and both together (:class:`Observation`), with their pixel-to-world geometry.

Frozen records of read-only arrays, so a frame handed to perception, a log or a reporter cannot be
changed under the others that hold it.  The conventions (image rows, depth, intrinsics,
extrinsics, heightmap cells) are stated in :mod:`capmj.sim.cameras`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np


def frozen(a: np.ndarray) -> np.ndarray:
    """``a``, made read-only in place."""
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class CameraFrame:
    """One rendered view (arrays are read-only)."""

    name: str
    rgb: np.ndarray
    """uint8 (H, W, 3)."""
    depth: np.ndarray
    """float32 (H, W) metres along the optical axis."""
    seg: np.ndarray | None
    """int32 (H, W) object id per pixel, 0 = robot/table/background; None when not rendered."""
    intrinsics: np.ndarray
    """float64 (3, 3)."""
    extrinsics: np.ndarray
    """float64 (4, 4) camera-to-world, OpenCV camera axes."""

    @property
    def shape(self) -> tuple[int, int]:
        return self.depth.shape  # type: ignore[return-value]

    def unproject(self, rows: Any, cols: Any) -> np.ndarray:
        """World points (N, 3) seen at integer pixels ``(rows, cols)``, using the rendered depth."""
        v = np.atleast_1d(np.asarray(rows))
        u = np.atleast_1d(np.asarray(cols))
        d = self.depth[v, u].astype(np.float64)
        k = self.intrinsics
        cam = np.stack([(u + 0.5 - k[0, 2]) / k[0, 0] * d, (v + 0.5 - k[1, 2]) / k[1, 1] * d, d], axis=-1)
        return cam @ self.extrinsics[:3, :3].T + self.extrinsics[:3, 3]

    def project(self, points: Any) -> np.ndarray:
        """Continuous pixel coordinates (N, 2) as (u, v) of world points; pixel index = floor."""
        p = np.atleast_2d(np.asarray(points, dtype=np.float64))
        r, t = self.extrinsics[:3, :3], self.extrinsics[:3, 3]
        cam = (p - t) @ r
        uv = cam[:, :2] / cam[:, 2:3]
        return uv * np.diag(self.intrinsics)[:2] + self.intrinsics[:2, 2]


@dataclass(frozen=True, eq=False)
class Heightmap:
    """Ravens-style top-down heightmap of the workspace (arrays are read-only)."""

    height: np.ndarray
    """float32 (320, 160) metres above the table, clipped at 0; rows = y ascending, cols = x ascending."""
    colormap: np.ndarray
    """uint8 (320, 160, 3) top-down colour."""
    seg: np.ndarray
    """int32 (320, 160) object ids."""
    pixel_size: float
    bounds: np.ndarray
    """(3, 2) workspace bounds: rows x, y, z; columns min, max."""

    def pixel_of(self, x: float, y: float) -> tuple[int, int]:
        """(row, col) of the cell containing world point (x, y) (a point on a cell edge: the upper cell)."""
        return (int(np.floor((y - self.bounds[1, 0]) / self.pixel_size + 1e-9)),
                int(np.floor((x - self.bounds[0, 0]) / self.pixel_size + 1e-9)))


@dataclass(frozen=True, eq=False)
class Observation:
    """Everything :meth:`capmj.sim.cameras.CameraRig.render_all` renders."""

    views: Mapping[str, CameraFrame]
    heightmap: Heightmap | None
    """None when :meth:`capmj.sim.cameras.CameraRig.render_all` was asked not to render it."""
