"""Fitting footprints to sets of cells: minimum-area rectangles (yaw) and the L of a fixture.

A block seen from above is a square whose orientation is the block's yaw (modulo 90°), a zone a
larger square, a fixture an L inside a 10 x 6 cm rectangle.  The minimum-area enclosing rectangle
of the cells' convex hull recovers centre, sides and angle without assuming which: one of its
sides is collinear with a hull edge (Freeman & Shapira 1975), so only the hull's edge directions
are tried.  Cells are squares, so the hull is taken over their four corners, which makes the
fitted sides the true extent rather than centre-to-centre distances.  A fixture is not fitted by
its rectangle but as an L (:func:`fit_l`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize
from scipy.spatial import ConvexHull, QhullError

from capmj.sim.shapes import FIXTURE_ORIGIN_IN, FIXTURE_WALLS


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
    """Fraction of the cells more than a cell off the fitted L's walls (0 = perfect)."""


_YAW_STEPS = 360
"""Yaw hypotheses (1° apart) of the L search in :func:`fit_l`."""


def _outside(u: np.ndarray, v: np.ndarray, slack: float) -> np.ndarray:
    """Distance (m) of fixture-frame points from the nearer of the L's two walls, each grown by
    ``slack`` (0 on a wall); any leading axes broadcast."""
    d = None
    for wall in FIXTURE_WALLS:
        (cx, cy, _), (hx, hy, _) = wall.centre, wall.half
        dx = np.maximum(np.abs(u - cx) - hx - slack, 0.0)
        dy = np.maximum(np.abs(v - cy) - hy - slack, 0.0)
        w = np.hypot(dx, dy)
        d = w if d is None else np.minimum(d, w)
    assert d is not None
    return d


def _to_frame(p: np.ndarray, x: float, y: float, yaw: float) -> tuple[np.ndarray, np.ndarray]:
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = p[:, 0] - x, p[:, 1] - y
    return c * dx + s * dy, -s * dx + c * dy


def fit_l(xy: np.ndarray, cell: float) -> LFit:
    """The L-fixture's origin and yaw that put the cells on its two walls.

    Why not the enclosing rectangle: the L's convex hull has a long diagonal edge (from the end of
    one wall to the end of the other), and with a few grown cells along a wall the minimum-area
    rectangle of a turned L aligns with that diagonal instead of the walls (``docs/perception.md``).
    The L is fitted as the shape it is instead:

    * every yaw 1° apart is tried; in the fixture's frame the long wall runs along +x from the
      corner and the short wall along +y (``mjcf/fixture.xml``), so under the right yaw the cells'
      smallest x and y are the corner's two outer faces, :data:`FIXTURE_ORIGIN_IN` out from the
      origin — that places the L for the yaw; the yaw whose L leaves the least squared distance
      of cells off its walls wins (a mirrored L cannot fit, so there is no mirror ambiguity);
    * the winner is refined by Nelder-Mead over (x, y, yaw) on the same cost.

    Cells hold the highest point falling in them, so they overhang a wall's two faces alike and the
    squared overhang is least with the wall centred on them.  Deterministic: a fixed grid and a
    fixed simplex.
    """
    p = np.asarray(xy, dtype=np.float64)
    overhang = cell / 2  # the outermost cells' centres lie about half a cell out of the faces
    yaws = np.linspace(-math.pi, math.pi, _YAW_STEPS, endpoint=False)
    c, s = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
    u = c * p[None, :, 0] + s * p[None, :, 1]  # (yaws, N): coordinates along the L's +x and +y
    v = -s * p[None, :, 0] + c * p[None, :, 1]
    u0 = u.min(axis=1, keepdims=True) + overhang + FIXTURE_ORIGIN_IN  # the origin's coordinates
    v0 = v.min(axis=1, keepdims=True) + overhang + FIXTURE_ORIGIN_IN
    cost = (_outside(u - u0, v - v0, 0.0) ** 2).sum(axis=1)
    k = int(np.argmin(cost))
    ox, oy = float(c[k, 0] * u0[k, 0] - s[k, 0] * v0[k, 0]), float(s[k, 0] * u0[k, 0] + c[k, 0] * v0[k, 0])

    def total(q: np.ndarray) -> float:
        return float((_outside(*_to_frame(p, q[0], q[1], q[2]), 0.0) ** 2).sum())

    res = minimize(total, np.array([ox, oy, float(yaws[k])]), method="Nelder-Mead",
                   options={"xatol": 1e-5, "fatol": 1e-12, "initial_simplex": np.array(
                       [[ox, oy, yaws[k]], [ox + 0.005, oy, yaws[k]], [ox, oy + 0.005, yaws[k]],
                        [ox, oy, yaws[k] + math.radians(2)]])})
    x, y, yaw = (float(v) for v in res.x)
    mismatch = float((_outside(*_to_frame(p, x, y, yaw), cell) > 0).mean())
    return LFit(x, y, math.remainder(yaw, 2 * math.pi), mismatch)


def l_corners(fit: LFit) -> np.ndarray:
    """The world corners (8, 2) of the fitted L's two walls (for its axis-aligned box)."""
    out = []
    c, s = math.cos(fit.yaw), math.sin(fit.yaw)
    for wall in FIXTURE_WALLS:
        (cx, cy, _), (hx, hy, _) = wall.centre, wall.half
        for du, dv in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)):
            u, v = cx + du, cy + dv
            out.append((fit.x + c * u - s * v, fit.y + s * u + c * v))
    return np.array(out)


__all__ = ["LFit", "Rect", "cell_corners", "fit_l", "l_corners", "min_area_rect", "square_yaw"]
