"""Where on the table: the workspace's named areas, and whether an object stayed where it was.

Area words follow the front-camera image: "top" = x in [0.25, 0.5], "bottom" = x in [0.5, 0.75],
"left" = y < 0, "right" = y > 0, and combinations such as "top left".
"""

from __future__ import annotations

import numpy as np

from capmj.sim.bounds import WORKSPACE
from capmj.sim.pose import Vector
from capmj.sim.state import SceneState
from capmj.tasks.predicates.tolerances import MOVE_TOL

WORKSPACE_X = (WORKSPACE.xmin, WORKSPACE.xmax)
WORKSPACE_Y = (WORKSPACE.ymin, WORKSPACE.ymax)
WORKSPACE_Z = (WORKSPACE.zmin, WORKSPACE.zmax)
"""The workspace's ranges (m), from :data:`capmj.sim.bounds.WORKSPACE`."""

_SPLIT_X, _SPLIT_Y = WORKSPACE.center
"""The lines that halve the workspace: x = 0.5 (top | bottom) and y = 0 (left | right)."""
_AREA_X = {"top": (WORKSPACE.xmin, _SPLIT_X), "bottom": (_SPLIT_X, WORKSPACE.xmax)}
_AREA_Y = {"left": (WORKSPACE.ymin, _SPLIT_Y), "right": (_SPLIT_Y, WORKSPACE.ymax)}
AREA_NAMES: tuple[str, ...] = (
    "top", "bottom", "left", "right", "top left", "top right", "bottom left", "bottom right",
)
QUADRANTS: tuple[str, ...] = ("top left", "top right", "bottom left", "bottom right")


def area_bounds(area: str) -> tuple[float, float, float, float]:
    """``(xmin, xmax, ymin, ymax)`` of a named area ("top", "left", "top left", "right bottom"…).

    Words are case-insensitive and may be joined by spaces, hyphens or underscores; an optional
    trailing "area" is ignored.  Unknown words raise ``ValueError`` naming the valid ones.
    """
    words = area.lower().replace("-", " ").replace("_", " ").split()
    if words and words[-1] == "area":
        words = words[:-1]
    x, y = WORKSPACE_X, WORKSPACE_Y
    seen_x = seen_y = False
    for w in words:
        if w in _AREA_X and not seen_x:
            x, seen_x = _AREA_X[w], True
        elif w in _AREA_Y and not seen_y:
            y, seen_y = _AREA_Y[w], True
        else:
            raise ValueError(f"unknown area {area!r}; valid areas: {', '.join(AREA_NAMES)}")
    if not words:
        raise ValueError(f"empty area name; valid areas: {', '.join(AREA_NAMES)}")
    return (x[0], x[1], y[0], y[1])


def in_area(pos: Vector, area: str | tuple[float, float, float, float]) -> bool:
    """Whether the xy of ``pos`` lies in the area (a name or ``(xmin, xmax, ymin, ymax)``).

    Tolerance: none.  Bounds are inclusive on the workspace edges; the split lines x = 0.5 and
    y = 0 belong to neither side (left is y < 0, right is y > 0, top x < 0.5, bottom x > 0.5), so
    a centre exactly on a split line is in no half.
    """
    b = area_bounds(area) if isinstance(area, str) else area
    x, y = float(pos[0]), float(pos[1])
    return _in_closed_or_split(x, b[0], b[1], _SPLIT_X) and _in_closed_or_split(y, b[2], b[3], _SPLIT_Y)


def _in_closed_or_split(v: float, lo: float, hi: float, split: float) -> bool:
    lo_ok = v > lo if lo == split else v >= lo
    hi_ok = v < hi if hi == split else v <= hi
    return lo_ok and hi_ok


def moved_less_than(state: SceneState, obj_id: int, start_pos: Vector, tol: float = MOVE_TOL) -> bool:
    """Whether the object's centre ends within ``tol`` (default 0.03 m, 3-D distance) of
    ``start_pos``."""
    return float(np.linalg.norm(state.pos(obj_id) - np.asarray(start_pos, dtype=float))) <= tol


__all__ = ["AREA_NAMES", "QUADRANTS", "WORKSPACE_X", "WORKSPACE_Y", "WORKSPACE_Z", "area_bounds", "in_area",
           "moved_less_than"]
