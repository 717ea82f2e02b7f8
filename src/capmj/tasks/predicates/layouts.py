"""Layouts of blocks on the table: grids and layers (the pyramid, the cube), footprints that touch
or support, rows along a line (the zone bisector).

Footprints are capmj's one footprint model (:mod:`capmj.sim.footprint`, the planner API's too):
the objects' real oriented squares, so "touching" and "resting on" mean what a reader of the
final snapshot would see, not a bounding circle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, Sequence

import numpy as np

from capmj.sim import footprint as _footprint
from capmj.sim.pose import Vector, to_frame_2d
from capmj.sim.state import SceneState
from capmj.tasks.predicates.labels import short_label
from capmj.tasks.predicates.stacks import toppled
from capmj.tasks.predicates.tolerances import Z_TOL

TOUCH_GAP = 0.001
"""Two footprints closer than this (m) touch."""


# --------------------------------------------------------------------------------------- grids and layers
def is_grid(
    points: Sequence[Vector],
    rows: int,
    cols: int,
    pitch_range: tuple[float, float] = (0.04, 0.06),
    align_tol: float = Z_TOL,
) -> tuple[bool, str]:
    """Whether the xy of ``points`` form a ``rows × cols`` grid at any orientation.

    Neighbour centre distances along rows and columns must lie in ``pitch_range`` (m) and every
    row and every column must be aligned within ``align_tol`` (m): the spread of the points'
    coordinate across the row (column) direction.  The grid's axes are estimated from the
    nearest-neighbour directions (modulo 90°); both row/column assignments are tried.
    """
    p = np.asarray(points, dtype=float).reshape(len(points), -1)[:, :2] if len(points) else np.zeros((0, 2))
    n = rows * cols
    if len(p) != n:
        return False, f"expected {n} points for a {rows}x{cols} grid, got {len(p)}"
    if n == 1:
        return True, "single point"
    d = np.hypot(p[:, None, 0] - p[None, :, 0], p[:, None, 1] - p[None, :, 1])
    np.fill_diagonal(d, np.inf)
    nn = d.argmin(axis=1)
    v = p[nn] - p
    ang = np.arctan2(v[:, 1], v[:, 0])
    theta = math.atan2(np.sin(4 * ang).sum(), np.cos(4 * ang).sum()) / 4
    local = to_frame_2d(p, theta)
    reasons = []
    for r_, c_, lc in ((rows, cols, local), (cols, rows, local[:, ::-1]),
                       (rows, cols, local[:, ::-1]), (cols, rows, local)):
        ok, why = _check_axis_grid(lc, r_, c_, pitch_range, align_tol)
        if ok:
            return True, f"{rows}x{cols} grid"
        reasons.append(why)
    return False, reasons[0]


def _check_axis_grid(lc: np.ndarray, rows: int, cols: int, pitch: tuple[float, float], tol: float) -> tuple[bool, str]:
    """Grid check in a frame where rows run along local x (rows differ in local y)."""
    order = np.argsort(lc[:, 1], kind="stable")
    grid = lc[order].reshape(rows, cols, 2)
    grid = np.take_along_axis(grid, np.argsort(grid[:, :, 0], axis=1, kind="stable")[:, :, None], axis=1)
    row_spread = np.ptp(grid[:, :, 1], axis=1)
    if np.any(row_spread > tol):
        return False, f"a row is misaligned by {row_spread.max():.3f} m (max {tol})"
    col_spread = np.ptp(grid[:, :, 0], axis=0)
    if np.any(col_spread > tol):
        return False, f"a column is misaligned by {col_spread.max():.3f} m (max {tol})"
    lo, hi = pitch
    if cols > 1:
        dr = np.hypot(*np.moveaxis(np.diff(grid, axis=1), -1, 0))
        if dr.min() < lo or dr.max() > hi:
            return False, f"row pitch {dr.min():.3f}–{dr.max():.3f} m outside {lo}–{hi}"
    if rows > 1:
        dc = np.hypot(*np.moveaxis(np.diff(grid, axis=0), -1, 0))
        if dc.min() < lo or dc.max() > hi:
            return False, f"column pitch {dc.min():.3f}–{dc.max():.3f} m outside {lo}–{hi}"
    return True, "grid"


def footprint(state: SceneState, obj_id: int):
    """The object's footprint on the table as a shapely geometry: capmj's one footprint model
    (:func:`capmj.sim.footprint.shape`, the planner API's too) at its pose in ``state`` — its
    oriented rectangle at the current yaw (a fixture: its two walls; tilted more than 15°: its
    world xy box), a disc for balls and bowls."""
    return _footprint.shape(state.spec(obj_id), state.poses[obj_id])


def touching_pairs(state: SceneState, ids: Sequence[int], gap: float = TOUCH_GAP) -> list[tuple[int, int, float]]:
    """Pairs ``(a, b, distance)`` of the objects whose footprints are closer than ``gap`` (m)."""
    fps = {i: footprint(state, i) for i in ids}
    ids = list(ids)
    return [(a, b, float(fps[a].distance(fps[b])))
            for k, a in enumerate(ids) for b in ids[k + 1:] if fps[a].distance(fps[b]) < gap]


def supporters(state: SceneState, upper: int, lowers: Iterable[int], tol: float = Z_TOL) -> list[int]:
    """The objects of ``lowers`` that ``upper`` rests on: the z gap of their centres is the mean of
    the two heights ± 0.015 m and their footprints overlap (area > 1 mm²)."""
    fu = footprint(state, upper)
    out = []
    for lo in lowers:
        gap = (state.spec(upper).height + state.spec(lo).height) / 2
        if abs(float(state.pos(upper)[2] - state.pos(lo)[2]) - gap) <= tol and fu.intersection(footprint(state, lo)).area > 1e-6:
            out.append(lo)
    return out


def is_layer(state: SceneState, ids: Sequence[int], rows: int, cols: int, level: int,
             pitch_range: tuple[float, float], align_tol: float = Z_TOL) -> tuple[bool, str]:
    """Whether the blocks form one ``rows × cols`` grid layer (:func:`is_grid`: neighbour pitch in
    ``pitch_range``, rows and columns aligned within ``align_tol``) at height ``level`` (0 = on the
    table: every centre at (level + ½) block heights ± 0.015 m), none tilted more than 15°."""
    for i in ids:
        if toppled(state, i):
            return False, f"{short_label(state.spec(i))} is tilted {math.degrees(state.poses[i].tilt):.0f}° (max 15°)"
        h = state.spec(i).height
        z = float(state.pos(i)[2])
        if abs(z - (level + 0.5) * h) > Z_TOL:
            return False, f"{short_label(state.spec(i))} is at z = {z:.3f} m, not on layer {level + 1} ({(level + 0.5) * h:.3f} ± {Z_TOL})"
    return is_grid([state.pos(i) for i in ids], rows, cols, pitch_range, align_tol)


# --------------------------------------------------------------------------------------- rows
ROW_LINE_TOL = 0.015
"""Row blocks: centre within this distance (m) of the line."""
ROW_PITCH_TOL = 0.015
"""Row blocks: neighbour centre spacing within this (m) of the required pitch."""
ROW_MID_TOL = 0.02
"""Row blocks: the mean of the centres within this distance (m) of the required midpoint."""


@dataclass(frozen=True)
class RowReport:
    """How well points form an evenly spaced row along a line (see :func:`row_on_line`).

    ``order`` are the input indices sorted along the line, ``offsets`` each point's distance from
    the line (input order), ``gaps`` the centre distances of neighbours in row order,
    ``midpoint_error`` the distance from the mean of the points to the required midpoint.
    """

    ok: bool
    order: tuple[int, ...]
    offsets: tuple[float, ...]
    gaps: tuple[float, ...]
    midpoint_error: float
    reasons: tuple[str, ...]


def row_on_line(
    points: Sequence[Vector],
    line_point: Vector,
    line_dir: Vector,
    pitch: float,
    *,
    line_tol: float = ROW_LINE_TOL,
    pitch_tol: float = ROW_PITCH_TOL,
    mid_tol: float = ROW_MID_TOL,
) -> RowReport:
    """Whether the xy of ``points`` lie on the line through ``line_point`` along ``line_dir``,
    evenly spaced and centred on ``line_point``.

    Tolerances: every centre within ``line_tol`` (0.015 m) of the line; every neighbour centre
    distance (in order along the line) within ``pitch_tol`` (0.015 m) of ``pitch``; the mean of
    the centres within ``mid_tol`` (0.02 m) of ``line_point``.  Reasons name point indices.
    """
    p = np.asarray(points, dtype=float).reshape(len(points), -1)[:, :2] if len(points) else np.zeros((0, 2))
    c = np.asarray(line_point, dtype=float)[:2]
    e = np.asarray(line_dir, dtype=float)[:2]
    e = e / np.linalg.norm(e)
    n = np.array([-e[1], e[0]])
    along = (p - c) @ e
    offsets = np.abs((p - c) @ n)
    order = np.argsort(along, kind="stable")
    gaps = np.hypot(*np.diff(p[order], axis=0).T) if len(p) > 1 else np.zeros(0)
    mid = float(np.hypot(*(p.mean(axis=0) - c))) if len(p) else math.inf
    reasons = [f"point {i} is {offsets[i]:.3f} m off the line (max {line_tol})"
               for i in range(len(p)) if offsets[i] > line_tol]
    reasons += [f"points {order[k]} and {order[k + 1]} are {g:.3f} m apart (need {pitch:.3f} ± {pitch_tol})"
                for k, g in enumerate(gaps) if abs(g - pitch) > pitch_tol]
    if mid > mid_tol:
        reasons.append(f"the row's midpoint is {mid:.3f} m from the required midpoint (max {mid_tol})")
    return RowReport(not reasons and len(p) > 0, tuple(int(i) for i in order), tuple(float(v) for v in offsets),
                     tuple(float(g) for g in gaps), mid, tuple(reasons))


__all__ = ["ROW_LINE_TOL", "ROW_MID_TOL", "ROW_PITCH_TOL", "RowReport", "TOUCH_GAP", "footprint", "is_grid", "is_layer",
           "row_on_line", "supporters", "touching_pairs"]
