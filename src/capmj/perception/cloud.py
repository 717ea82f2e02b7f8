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


def _upright(points: np.ndarray) -> np.ndarray:
    """(H, W) bool: the surface at each pixel faces up (false at depth edges and on the border)."""
    du = points[:-1, 1:] - points[:-1, :-1]
    dv = points[1:, :-1] - points[:-1, :-1]
    n = np.cross(du, dv)
    norm = np.linalg.norm(n, axis=-1)
    step = np.maximum(np.linalg.norm(du, axis=-1), np.linalg.norm(dv, axis=-1))
    with np.errstate(invalid="ignore", divide="ignore"):
        ok = (np.abs(n[..., 2]) > UPRIGHT_COS * norm) & (step < 0.006) & (norm > 0)
    out = np.zeros(points.shape[:2], dtype=bool)
    out[:-1, :-1] = ok
    return out


def _view_points(view: CameraImage) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points (N, 3), rgb (N, 3), upright (N,)) of the pixels of one view over the workspace."""
    pts = view.points()
    up = _upright(pts)
    w = WORKSPACE
    keep = ((view.depth < _DEPTH_FAR) & (pts[..., 0] >= w.xmin) & (pts[..., 0] < w.xmax)
            & (pts[..., 1] >= w.ymin) & (pts[..., 1] < w.ymax) & (pts[..., 2] > -0.01) & (pts[..., 2] < Z_MAX))
    return pts[keep], view.rgb[keep], up[keep]


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
    order = np.lexsort((pts[:, 2], flat))  # by cell, then height: each cell's last entry is its top
    flat_sorted = flat[order]
    last = order[np.r_[flat_sorted[1:] != flat_sorted[:-1], True]]
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
