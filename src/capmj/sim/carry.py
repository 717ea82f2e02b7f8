"""A carry that clears only what it passes over: the sloped transit for far-corner picks.

Why: the pick-and-place primitive carries at one transit height that clears every object on the
table (:meth:`capmj.sim.primitives.Primitives.transit_height`).  Above a far corner of the
workspace that height can be out of the UR5e's reach with the tool pointing down (a block at
(0.695, 0.398) cannot be lifted to 0.376 m, the height over a seven-block tower elsewhere), and
the primitive then failed although nothing near the pick point needs that height.  Only the
objects under the carried object's corridor need clearing, so the carry can lift as high as the
arm reaches there, rise on a slope towards the place point, and go on level once it must clear
something taller.  The primitive only takes this path when the straight lift is unreachable, so
every ordinary carry is unchanged.
"""

from __future__ import annotations

import numpy as np

from capmj.sim.ik import SuctionIK
from capmj.sim.world import World

REACH_STEP = 0.01
"""m: the grid on which :func:`reach_height` searches the highest reachable tip height."""

REACH_MARGIN = 0.01
"""m kept below the highest analytically reachable tip height: the edge of the reach is the
straight-elbow singularity, where a line would crawl or be refused."""


def corridor(world: World, a: np.ndarray, b: np.ndarray, radius: float,
             exclude: int | None = None) -> list[tuple[float, float, float]]:
    """What a disc of ``radius`` moving from xy ``a`` to xy ``b`` passes over: per object (but
    ``exclude``) whose world box it overlaps, ``(s_in, s_out, top)`` with the path fractions (0 at
    ``a``, 1 at ``b``) where it does and the box's top (m).

    Each box is grown by ``radius`` (square corners: conservative) and the segment clipped against
    it (Liang–Barsky).
    """
    out = []
    d = np.asarray(b, float)[:2] - np.asarray(a, float)[:2]
    ids, los, his = world.object_boxes()
    for i, lo, hi in zip(ids.tolist(), los, his):
        if i == exclude:
            continue
        s0, s1 = 0.0, 1.0
        for k in range(2):
            lo_k, hi_k = lo[k] - radius, hi[k] + radius
            if abs(d[k]) < 1e-12:
                if not lo_k <= a[k] <= hi_k:
                    s0, s1 = 1.0, 0.0
                continue
            t0, t1 = sorted(((lo_k - a[k]) / d[k], (hi_k - a[k]) / d[k]))
            s0, s1 = max(s0, t0), min(s1, t1)
        if s0 <= s1:
            out.append((s0, s1, float(hi[2])))
    return out


def reach_height(ik: SuctionIK, q_near: np.ndarray, xy: np.ndarray, yaw: float, z_hi: float,
                 z_lo: float) -> float | None:
    """The highest tip height (m), at most ``z_hi``, at which the tool reaches ``xy`` pointing down
    (analytic IK near ``q_near``), :data:`REACH_MARGIN` below the edge of the reach; None if that
    is below ``z_lo``."""
    z = z_hi
    while z >= z_lo:
        if ik.solve_analytic(np.array([xy[0], xy[1], z]), yaw, q_near) is not None:
            return z if z == z_hi else (z - REACH_MARGIN if z - REACH_MARGIN >= z_lo else None)
        z -= REACH_STEP
    return None


def sloped_transit(world: World, ik: SuctionIK, a: np.ndarray, b: np.ndarray, yaw: float, radius: float,
                   top: float, low: float, need_above: float, exclude: int | None) -> list[np.ndarray] | None:
    """Tip waypoints of a carry from xy ``a`` (straight up there first) to above xy ``b``, or None
    if there is none: each reachable, and the tip at least ``need_above`` over every object top
    under the corridor of ``radius`` (:func:`corridor`), where ``need_above`` is the clearance
    plus how far the carried object hangs below the tip.

    The carry lifts at ``a`` as high as it reaches (``z0``, at most the full transit height
    ``top``, at least ``low``), rises on a slope to the height ``z1`` reachable above ``b`` by
    where its corridor first meets an object too tall to clear at ``z0`` (if any), and goes on
    level from there.  A line's height over an object's stretch is lowest at one of the stretch's
    ends, so checking those suffices.
    """
    q = world.arm_ctrl()
    z0 = reach_height(ik, q, a, yaw, top, low)
    z1 = reach_height(ik, q, b, yaw, top, low)
    if z0 is None or z1 is None:
        return None
    need = [(s_in, s_out, obj_top + need_above) for s_in, s_out, obj_top in corridor(world, a, b, radius, exclude)]
    brk = min((s_in for s_in, _, z in need if z > z0), default=1.0)  # where z1 must be reached
    if brk <= 0.0:
        return None
    mid = np.asarray(a, float)[:2] + brk * (np.asarray(b, float)[:2] - np.asarray(a, float)[:2])
    if brk < 1.0 and reach_height(ik, q, mid, yaw, z1, z1) is None:
        return None

    def height(s: float) -> float:
        return z0 + min(1.0, s / brk) * (z1 - z0)

    for s_in, s_out, z in need:
        if min(height(s_in), height(min(s_out, brk)), height(s_out)) < z:
            return None
    points = [np.array([a[0], a[1], z0]), np.array([mid[0], mid[1], z1])]
    if brk < 1.0:
        points.append(np.array([b[0], b[1], z1]))
    return points
