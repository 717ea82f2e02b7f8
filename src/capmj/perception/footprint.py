"""Fitting footprints to sets of cells: minimum-area rectangles (yaw) and the L of a fixture.

A block seen from above is a square whose orientation is the block's yaw (modulo 90°), a zone a
larger square, a fixture an L inside a 10 x 6 cm rectangle.  The minimum-area enclosing rectangle
of the cells' convex hull recovers centre, sides and angle without assuming which: one of its
sides is collinear with a hull edge (Freeman & Shapira 1975), so only the hull's edge directions
are tried.  Cells are squares, so the hull is taken over their four corners, which makes the
fitted sides the true extent rather than centre-to-centre distances.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from capmj.sim.objects import FIXTURE_WALL
from capmj.sim.shapes import FIXTURE_ORIGIN_IN


@dataclass(frozen=True)
class Rect:
    """An oriented rectangle: centre (m), side lengths with ``length >= width``, angle of the
    long side in (-π/2, π/2]."""

    cx: float
    cy: float
    length: float
    width: float
    angle: float

    @property
    def area(self) -> float:
        return self.length * self.width

    @property
    def axes(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit vectors along the long and the short side."""
        c, s = math.cos(self.angle), math.sin(self.angle)
        return np.array([c, s]), np.array([-s, c])


def _wrap_half_turn(a: float) -> float:
    """An angle in (-π/2, π/2] (a rectangle's long side has no direction)."""
    a = math.remainder(a, math.pi)
    return math.pi / 2 if a <= -math.pi / 2 else a


def cell_corners(xy: np.ndarray, cell: float) -> np.ndarray:
    """The four corners (4N, 2) of square cells centred at ``xy`` (N, 2)."""
    h = cell / 2
    offsets = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
    return (np.asarray(xy)[:, None, :] + offsets[None]).reshape(-1, 2)


def min_area_rect(points: np.ndarray) -> Rect:
    """The smallest-area rectangle enclosing ``points`` (N, 2); N >= 1 (degenerate sets give a
    zero side).  Deterministic: ties go to the first hull edge in Qhull's order."""
    p = np.asarray(points, dtype=np.float64)
    try:
        hull = p[ConvexHull(p).vertices]
    except (QhullError, ValueError):  # collinear or too few points
        hull = p
    if len(hull) < 2:
        return Rect(float(hull[0, 0]), float(hull[0, 1]), 0.0, 0.0, 0.0)
    edges = np.diff(np.vstack([hull, hull[:1]]), axis=0)
    angles = np.unique(np.round(np.mod(np.arctan2(edges[:, 1], edges[:, 0]), math.pi / 2), 12))
    best: tuple[float, float, np.ndarray, np.ndarray] | None = None
    for a in angles:
        c, s = math.cos(a), math.sin(a)
        rot = hull @ np.array([[c, -s], [s, c]])  # coordinates along (c, s) and (-s, c)
        lo, hi = rot.min(axis=0), rot.max(axis=0)
        area = float(np.prod(hi - lo))
        if best is None or area < best[0] - 1e-12:
            best = (area, float(a), lo, hi)
    assert best is not None
    _, a, lo, hi = best
    mid = (lo + hi) / 2
    c, s = math.cos(a), math.sin(a)
    centre = mid[0] * np.array([c, s]) + mid[1] * np.array([-s, c])
    du, dv = float(hi[0] - lo[0]), float(hi[1] - lo[1])
    if dv > du:
        du, dv, a = dv, du, a + math.pi / 2
    return Rect(float(centre[0]), float(centre[1]), du, dv, _wrap_half_turn(a))


def square_yaw(rect: Rect) -> float:
    """The yaw of a square footprint in [-π/4, π/4) (a square repeats every 90°)."""
    return (rect.angle + math.pi / 4) % (math.pi / 2) - math.pi / 4


@dataclass(frozen=True)
class LFit:
    """A fixture's pose: its origin (slot (0, 0), the body origin) and yaw, plus the fit residue."""

    x: float
    y: float
    yaw: float
    mismatch: float
    """Fraction of the cells off the fitted L's walls (0 = perfect)."""


def fit_l(xy: np.ndarray, rect: Rect, cell: float) -> LFit:
    """The L-fixture in its enclosing rectangle: which corner the walls meet at fixes the yaw.

    In the fixture's frame the long wall runs along +x from the corner and the short wall along
    +y (:data:`capmj.sim.shapes.FIXTURE_WALLS`), and the origin is ``FIXTURE_ORIGIN_IN`` in from the corner
    along each (wall + clearance + half a slot).  Each of the four corner hypotheses (the long side's two directions x
    the short side's two) is scored by the cells lying on its two walls; the best wins.
    """
    p = np.asarray(xy, dtype=np.float64) - (rect.cx, rect.cy)
    along, across = rect.axes
    u, v = p @ along, p @ across
    half_l, half_w = rect.length / 2, rect.width / 2
    wall = FIXTURE_WALL + cell
    best: LFit | None = None
    for su in (1.0, -1.0):
        for sv in (1.0, -1.0):
            # Corner at (-su*half_l, -sv*half_w); local +x = su*along, local +y = sv*across.
            lu, lv = su * u + half_l, sv * v + half_w  # distances from the corner's two sides
            on = (lv <= wall) | (lu <= wall)
            mismatch = float(1.0 - on.mean())
            x_axis, y_axis = su * along, sv * across
            if x_axis[0] * y_axis[1] - x_axis[1] * y_axis[0] < 0:  # a mirrored L cannot be the fixture
                mismatch += 1.0
            origin = (np.array([rect.cx, rect.cy]) - half_l * x_axis - half_w * y_axis
                      + FIXTURE_ORIGIN_IN * (x_axis + y_axis))
            yaw = math.atan2(float(x_axis[1]), float(x_axis[0]))
            if best is None or mismatch < best.mismatch - 1e-9:
                best = LFit(float(origin[0]), float(origin[1]), yaw, mismatch)
    assert best is not None
    return best


__all__ = ["LFit", "Rect", "cell_corners", "fit_l", "min_area_rect", "square_yaw"]
