"""Fusing calibrated RGB-D views into one top-down map of the table (Ravens-style heightmap).

Every pixel of every view is back-projected through its depth and calibration to a world point;
the points over the workspace are binned into a grid of square cells and each cell keeps its
highest point (what a camera straight above would see).  Three oblique views see around one
another's occlusions, including the arm's: points above :data:`Z_MAX` (the arm parked over the
table, whose suction tip rests at 0.30 m) are dropped before binning, so the arm leaves holes
in one view that the others fill, never phantom objects.

Besides its height a cell keeps the colour of its highest point (as CIELAB), the camera that
saw it, and whether the surface there faces up (normal from the depth image's neighbours).  Only
up-facing pixels are lit like the table, so only they are trusted for naming colours; side faces
are darker by a factor that depends on their orientation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmj.perception.colour import ColourModel, camera_gain, srgb_to_lab
from capmj.perception.rgbd import CameraImage, RGBDBundle
from capmj.sim.bounds import WORKSPACE

CELL = 0.0025
"""Grid cell edge (m): a tiny 2 cm block covers 8 x 8 cells."""
Z_MAX = 0.28
"""Points higher than this are the arm, not the scene (towers of five 4 cm blocks reach 0.20 m)."""
TABLE_Z = 0.0002
"""Height of the table top (``mjcf/table.xml``: the workspace box's upper face)."""
TABLE_TOL = 0.0004
"""Points within this of :data:`TABLE_Z` are the bare table (a zone's face is 0.8 mm above it)."""
UPRIGHT_COS = 0.9
"""A surface faces up when its normal is within ~26 degrees of +z."""
_DEPTH_FAR = 4.99


@dataclass(frozen=True, eq=False)
class TopDownMap:
    """The fused view from above; arrays are (rows = y ascending, cols = x ascending)."""

    height: np.ndarray
    """float64 (R, C) metres above the table top; NaN where no camera saw the cell."""
    lab: np.ndarray
    """float64 (R, C, 3) CIELAB of each cell's highest point (NaN where unseen)."""
    camera: np.ndarray
    """int64 (R, C) index of the view that saw the highest point, -1 where unseen."""
    upright: np.ndarray
    """bool (R, C): the highest point lies on an up-facing surface."""
    colours: ColourModel
    """The palette as each view sees it (gains measured on the table)."""
    origin: tuple[float, float]
    """World (x, y) of the corner of cell (0, 0)."""
    cell: float

    @property
    def seen(self) -> np.ndarray:
        return np.isfinite(self.height)

    def xy(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """World (x, y) (N, 2) of cell centres."""
        return np.stack([self.origin[0] + (np.asarray(cols) + 0.5) * self.cell,
                         self.origin[1] + (np.asarray(rows) + 0.5) * self.cell], axis=-1)


def _view_points(view: CameraImage) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points (N, 3), rgb (N, 3), upright (N,)) of the pixels of one view over the workspace.

    A pixel is upright when the plane through it and its right and lower neighbours faces up;
    pixels at depth edges (a neighbour farther than 6 mm) and on the image border are not.  The
    normals are computed only for the pixels kept, in float32: this is the perceiver's hot loop.
    It works on one (H, W) image per world coordinate and gathers by flat pixel index — three
    contiguous planes instead of an (H, W, 3) array indexed by (row, col) pairs, 4.5x faster with
    the same float32 operations in the same order, so the same bits.
    """
    h, w = view.shape
    k, pose = view.intrinsics, view.extrinsics
    rot = pose[:3, :3].astype(np.float32)
    origin = pose[:3, 3].astype(np.float32)
    a = ((np.arange(w) + 0.5 - k[0, 2]) / k[0, 0]).astype(np.float32)
    b = ((np.arange(h) + 0.5 - k[1, 2]) / k[1, 1]).astype(np.float32)
    depth = view.depth
    # world coordinate i of every pixel: depth x (its ray's direction per unit depth) + camera origin
    x, y, z = (depth * (a[None, :] * rot[i, 0] + b[:, None] * rot[i, 1] + rot[i, 2]) + origin[i] for i in range(3))
    ws = WORKSPACE
    keep = ((depth < _DEPTH_FAR) & (x >= ws.xmin) & (x < ws.xmax) & (y >= ws.ymin) & (y < ws.ymax)
            & (z > -0.01) & (z < Z_MAX))
    keep[-1, :] = False
    keep[:, -1] = False
    at = np.flatnonzero(keep)
    x, y, z = x.ravel(), y.ravel(), z.ravel()
    x0, y0, z0 = x[at], y[at], z[at]
    right, below = at + 1, at + w
    dux, duy, duz = x[right] - x0, y[right] - y0, z[right] - z0
    dvx, dvy, dvz = x[below] - x0, y[below] - y0, z[below] - z0
    nx = duy * dvz - duz * dvy
    ny = duz * dvx - dux * dvz
    nz = dux * dvy - duy * dvx
    n2 = nx * nx + ny * ny + nz * nz
    step2 = np.maximum(dux * dux + duy * duy + duz * duz, dvx * dvx + dvy * dvy + dvz * dvz)
    up = (nz * nz > UPRIGHT_COS ** 2 * n2) & (n2 > 0) & (step2 < 0.006 ** 2)
    return np.stack([x0, y0, z0], axis=1).astype(np.float64), view.rgb.reshape(-1, 3)[at], up


def fuse(bundle: RGBDBundle, cell: float = CELL) -> TopDownMap:
    """The top-down map of a bundle: highest point per cell over all views (see module docstring)."""
    w = WORKSPACE
    cols = int(round((w.xmax - w.xmin) / cell))
    rows = int(round((w.ymax - w.ymin) / cell))
    all_pts, all_rgb, all_up, all_cam, gains = [], [], [], [], []
    for k, view in enumerate(bundle.views):
        pts, rgb, up = _view_points(view)
        table = up & (np.abs(pts[:, 2] - TABLE_Z) < TABLE_TOL)
        gains.append(camera_gain(rgb[table]))
        all_pts.append(pts)
        all_rgb.append(rgb)
        all_up.append(up)
        all_cam.append(np.full(len(pts), k, dtype=np.int64))
    pts = np.concatenate(all_pts)
    rgb = np.concatenate(all_rgb)
    up = np.concatenate(all_up)
    cam = np.concatenate(all_cam)
    c = np.clip(((pts[:, 0] - w.xmin) / cell).astype(np.int64), 0, cols - 1)
    r = np.clip(((pts[:, 1] - w.ymin) / cell).astype(np.int64), 0, rows - 1)
    flat = r * cols + c
    top = np.full(rows * cols, -np.inf)
    np.maximum.at(top, flat, pts[:, 2])
    winners = np.flatnonzero(pts[:, 2] == top[flat])
    first = np.full(rows * cols, len(pts), dtype=np.int64)
    np.minimum.at(first, flat[winners], winners)  # ties: the first point in view order, deterministic
    last = first[first < len(pts)]
    height = np.full(rows * cols, np.nan)
    lab = np.full((rows * cols, 3), np.nan)
    camera = np.full(rows * cols, -1, dtype=np.int64)
    upright = np.zeros(rows * cols, dtype=bool)
    cells = flat[last]
    height[cells] = np.maximum(pts[last, 2] - TABLE_Z, 0.0)
    lab[cells] = srgb_to_lab(rgb[last])
    camera[cells] = cam[last]
    upright[cells] = up[last]
    return TopDownMap(height=height.reshape(rows, cols), lab=lab.reshape(rows, cols, 3),
                      camera=camera.reshape(rows, cols), upright=upright.reshape(rows, cols),
                      colours=ColourModel.from_gains(np.stack(gains)), origin=(w.xmin, w.ymin), cell=cell)


__all__ = ["CELL", "TABLE_Z", "Z_MAX", "TopDownMap", "fuse"]
