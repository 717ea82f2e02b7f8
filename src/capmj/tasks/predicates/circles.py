"""Circles of blocks: a least-squares circle, alternating colours around it, concentric rings."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from capmj.sim.pose import Vector
from capmj.sim.state import SceneState
from capmj.tasks.predicates.labels import short_label

CIRCLE_TOL = 0.01
"""Every centre of a circle lies within this distance (m) of the fitted circle."""
CENTRE_TOL = 0.02
"""Two circles (or a circle and the ball) are concentric when their centres are this close (m)."""


def fit_circle(points: Sequence[Vector]) -> tuple[np.ndarray, float, float]:
    """Least-squares circle through the xy of ``points``: ``(centre_xy, radius, max_residual)``.

    ``max_residual`` is the largest |distance to centre − radius| (m).  Fewer than three points or
    collinear points give ``radius = max_residual = inf``.
    """
    p = np.asarray(points, dtype=float).reshape(len(points), -1)[:, :2] if len(points) else np.zeros((0, 2))
    if len(p) < 3:
        return (p.mean(axis=0) if len(p) else np.zeros(2)), math.inf, math.inf
    # Kasa fit on centred coordinates: x² + y² + D x + E y + F = 0.
    m = p.mean(axis=0)
    q = p - m
    a = np.column_stack([q[:, 0], q[:, 1], np.ones(len(q))])
    b = -(q ** 2).sum(axis=1)
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    if np.linalg.matrix_rank(a) < 3:
        return m, math.inf, math.inf
    cx, cy = -sol[0] / 2, -sol[1] / 2
    r2 = cx * cx + cy * cy - sol[2]
    if not np.isfinite(r2) or r2 <= 0:
        return m, math.inf, math.inf
    r = math.sqrt(r2)
    if r > 1e3:  # numerically collinear
        return m, math.inf, math.inf
    centre = np.array([cx, cy]) + m
    resid = np.abs(np.hypot(p[:, 0] - centre[0], p[:, 1] - centre[1]) - r)
    return centre, float(r), float(resid.max())


def circle_of(state: SceneState, ids: Sequence[int], tol: float = CIRCLE_TOL,
              min_radius: float = 0.0) -> tuple[bool, np.ndarray, float, str]:
    """Whether the xy centres of ``ids`` lie on one circle: ``(ok, centre, radius, reason)``.

    The circle is the least-squares fit (:func:`fit_circle`); every centre must be within ``tol``
    (0.01 m) of it and the radius at least ``min_radius`` (m)."""
    c, r, res = fit_circle([state.pos(i) for i in ids])
    if not math.isfinite(r):
        return False, c, r, f"{len(ids)} centres do not span a circle (fewer than 3 or collinear)"
    if res > tol:
        d = [abs(math.hypot(*(state.pos(i)[:2] - c)) - r) for i in ids]
        worst = ids[int(np.argmax(d))]
        return False, c, r, (f"{short_label(state.spec(worst))} is {max(d):.3f} m off the fitted circle "
                             f"(radius {r:.3f} m, max {tol})")
    if r < min_radius:
        return False, c, r, f"circle radius {r:.3f} m is below {min_radius:.3f} m"
    return True, c, r, f"circle of radius {r:.3f} m at ({c[0]:.3f}, {c[1]:.3f})"


def angular_order(state: SceneState, ids: Sequence[int], centre: Vector) -> list[int]:
    """``ids`` sorted by the angle of their xy centre around ``centre``."""
    return sorted(ids, key=lambda i: math.atan2(state.pos(i)[1] - centre[1], state.pos(i)[0] - centre[0]))


def alternates(state: SceneState, ids: Sequence[int], centre: Vector) -> tuple[bool, str]:
    """Whether colours alternate going round ``centre`` (cyclically: two colours, equal counts,
    no two angular neighbours of one colour); the reason names a same-coloured neighbour pair."""
    order = angular_order(state, ids, centre)
    colours = {state.spec(i).color for i in ids}
    if len(colours) != 2:
        return False, f"alternation needs exactly two colours, got {', '.join(sorted(colours))}"
    for a, b in zip(order, order[1:] + order[:1]):
        if state.spec(a).color == state.spec(b).color:
            return False, f"{short_label(state.spec(a))} and {short_label(state.spec(b))} are neighbours of the same colour"
    return True, "colours alternate"


def concentric(state: SceneState, ring_a: Sequence[int], ring_b: Sequence[int], centre_tol: float = CENTRE_TOL,
               min_gap: float = 0.04, tol: float = CIRCLE_TOL) -> tuple[bool, str]:
    """Whether ``ring_a`` and ``ring_b`` each lie on a circle (:func:`circle_of`, ``tol``), the two
    centres within ``centre_tol`` (0.02 m) and the radii at least ``min_gap`` (m) apart."""
    ok_a, ca, ra, why_a = circle_of(state, ring_a, tol)
    if not ok_a:
        return False, why_a
    ok_b, cb, rb, why_b = circle_of(state, ring_b, tol)
    if not ok_b:
        return False, why_b
    d = float(np.hypot(*(ca - cb)))
    if d > centre_tol:
        return False, f"the circle centres are {d:.3f} m apart (max {centre_tol})"
    if abs(ra - rb) < min_gap:
        return False, f"the radii {ra:.3f} m and {rb:.3f} m differ by less than {min_gap} m"
    return True, f"concentric circles of radii {min(ra, rb):.3f} m and {max(ra, rb):.3f} m"


__all__ = ["CENTRE_TOL", "CIRCLE_TOL", "alternates", "angular_order", "circle_of", "concentric", "fit_circle"]
