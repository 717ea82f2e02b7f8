"""Planning one straight line of the suction tip: IK along the line, refined until joint-space
interpolation stays on it, then timed as fast as the limits allow.

Why this shape: the line is solved through :class:`~capmj.sim.ik.SuctionIK` once, at path points
chosen so that cubic Hermite interpolation in joint space between neighbours (with the joint rates
from the Jacobian) keeps the tip within ``path_tol`` of the line (checked by forward kinematics at
every interval's midpoint, where the interpolation error of a smooth path peaks).  The line is then
timed, without solving it again, as fast as the tool's speed and acceleration caps and the joints'
limits allow at each point (:func:`capmj.sim.timing.time_optimal`), and sampled every ``ik_dt``
seconds from that table.  Solving every time sample instead (the first version) took ~220 IK
solves per pick-and-place, more wall time than the physics; linear interpolation needed ~45; the
Hermite table needs ~8.  :class:`capmj.sim.motion.Motion` tracks the plans made here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmj.sim.ik import SuctionIK
from capmj.sim.motion_config import MotionConfig
from capmj.sim.timing import time_optimal

# Segment planning thresholds: numerical limits of the planner itself, not motion tuning (that is
# MotionConfig).  Changing one changes which lines plan and how they are timed.

MAX_JOINT_STEP = 0.5
"""rad: the largest change of any joint between two consecutive timing samples (``ik_dt`` apart).
At the 0.02 s sample spacing that is 25 rad/s, eight times the joint speed limit: no retiming can
make such a jump trackable, it means the table crossed to another IK branch (a wrist
singularity), so the line is refused rather than whipping the arm round."""

TIMING_GRID = 0.01
"""m of path (rotation counted as in the timing) between the points where the time-optimal timing
enforces the joint limits; the joints' rates change little over 1 cm of a line."""

TIMING_SPEED_SHARE = 0.98
"""The timing plans to 98 % of the joint speed limit, so the grid's discretisation rarely lets a
sampled trajectory slip over it (which costs a retiming)."""

TIMING_ACCEL_SHARE = 0.9
"""The timing plans to 90 % of the joint acceleration limit: the rest is room for the term it
leaves out, the path's curvature in joint space (``q'' ṡ²``), so a retiming is rare (the
measurement: ``docs/speed.md``)."""

RETIME_MARGIN = 1.05
"""Each retiming slows down by the measured over-limit ratio times this: 5 % more than the ratio, so
the next try (whose samples shift) lands under the joint limits instead of just over them again."""

RETIME_RATIO_TOL = 1.0001
"""A timing whose worst joint speed/acceleration ratio is at most this counts as within limits
(0.01 % slack for rounding, so an exactly-at-limit timing is not stretched again)."""

MAX_SLOWDOWN = 20.0
"""The most the joints may slow a line below its Cartesian speed anywhere (nominal speed / 20).  A
line that needs more is a crawl through a near-singular pose: it is refused as unreachable instead."""

RETIME_TRIES = 6
"""Timings computed for one line at most; if the last is still over the limits it is used as it is
(the servos then lag slightly and ``converge`` closes the gap)."""

MIN_BISECT_PATH = 1e-3
"""m: a line's table is refined by bisection only down to 1 mm of path; an interval that short
still off the line means the IK branch flipped inside it, and the line is refused."""


@dataclass(frozen=True)
class SegmentPlan:
    """Joint-space samples of one segment, ``dt`` seconds apart, tracked by
    :meth:`capmj.sim.motion.Motion.execute`;
    ``a`` is the path parameter (0 to 1) of each sample along a line of effective length ``extent``
    (None for a joint-space move), so a corner blend knows how far a sample is from the line's ends."""

    qs: np.ndarray   # (k, 6) joint samples
    dt: float        # seconds between samples
    a: np.ndarray | None = None
    extent: float = 0.0


@dataclass(frozen=True)
class LineTable:
    """IK solutions ``q`` along a line at path parameters ``s`` (ascending, 0 to 1) with their
    joint rates ``dq/ds``: the line, interpolated as a cubic Hermite spline."""

    s: np.ndarray    # (k,)
    q: np.ndarray    # (k, 6)
    dq: np.ndarray   # (k, 6)

    def _locate(self, a: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Interval index, interval length and local parameter in [0, 1] of path parameters ``a``."""
        s = self.s
        i = np.clip(np.searchsorted(s, a, side="right") - 1, 0, len(s) - 2)
        h = (s[i + 1] - s[i])[:, None]
        return i, h, (np.asarray(a) - s[i])[:, None] / h

    def at(self, a: np.ndarray) -> np.ndarray:
        """Joints at path parameters ``a`` (each in [0, 1])."""
        q, dq = self.q, self.dq
        i, h, t = self._locate(a)
        t2, t3 = t * t, t * t * t
        return ((2 * t3 - 3 * t2 + 1) * q[i] + (t3 - 2 * t2 + t) * h * dq[i]
                + (-2 * t3 + 3 * t2) * q[i + 1] + (t3 - t2) * h * dq[i + 1])

    def derivative(self, a: np.ndarray) -> np.ndarray:
        """``dq/ds`` of the spline at path parameters ``a``."""
        q, dq = self.q, self.dq
        i, h, t = self._locate(a)
        t2 = t * t
        return (6 * t2 - 6 * t) * (q[i] - q[i + 1]) / h + (3 * t2 - 4 * t + 1) * dq[i] + (3 * t2 - 2 * t) * dq[i + 1]


def timing_grid(extent: float, slow: float) -> tuple[np.ndarray, float]:
    """Path parameters at which a line of effective length ``extent`` is timed, ``TIMING_GRID``
    apart (at least two intervals: a line from rest to rest needs one to speed up and one to
    brake), and the parameter where its last ``slow`` (the guarded part) begins, a grid point."""
    split = (extent - slow) / extent
    n = max(2, int(np.ceil(extent / TIMING_GRID)))
    if slow <= 0 or split <= 0:
        return np.linspace(0.0, 1.0, n + 1), (1.0 if slow <= 0 else 0.0)
    n_fast = max(1, int(np.ceil(n * split)))
    n_slow = max(1, n - n_fast)
    return np.concatenate([np.linspace(0.0, split, n_fast + 1), np.linspace(split, 1.0, n_slow + 1)[1:]]), split


def line_table(ik: SuctionIK, cfg: MotionConfig, start: np.ndarray, end: np.ndarray, yaw0: float, yaw1: float,
               q_start: np.ndarray, extent: float) -> LineTable | None:
    """IK solutions along the line, with their joint rates, such that cubic Hermite
    interpolation between neighbours stays within ``path_tol``/``path_rot_tol``; None if a
    point is unreachable or the IK branch flips (a wrist singularity).  ``extent`` is the
    line's effective length (rotation counted as in the timing).

    Hermite interpolation uses the joint rate dq/ds at each point (from the Jacobian), so its
    error shrinks with the fourth power of the spacing instead of the square: a line needs a
    few solves where linear interpolation needed one every few centimetres.  The interpolation
    error of both peaks at an interval's midpoint, which is where it is checked.
    """
    n = max(1, int(np.ceil(extent / cfg.path_step)))
    min_ds = MIN_BISECT_PATH / max(extent, MIN_BISECT_PATH)  # in s units; at most the whole line
    lin, yaw_rate = end - start, yaw1 - yaw0  # d(tip)/ds and d(yaw)/ds

    def point(a: float) -> tuple[np.ndarray, float]:
        return start + a * lin, yaw0 + a * yaw_rate

    ss, qs, ms = [0.0], [q_start], [ik.joint_rate(q_start, lin, yaw_rate)]
    offset = None  # the last solve's analytic-model error, seeding the next (see SuctionIK.solve)
    for k in range(1, n + 1):  # coarse chain, each solve seeded by the previous one
        res = ik.solve(*point(k / n), qs[-1], offset=offset)
        if res.q is None:
            return None
        ss.append(k / n)
        qs.append(res.q)
        ms.append(ik.joint_rate(res.q, lin, yaw_rate))
        offset = res.offset
    i = 0
    while i < len(ss) - 1:  # refine each interval until its midpoint is within tolerance
        a, b = ss[i], ss[i + 1]
        mid = 0.5 * (a + b)
        q_mid = 0.5 * (qs[i] + qs[i + 1]) + (b - a) / 8 * (ms[i] - ms[i + 1])  # Hermite at t = 1/2
        pos, yaw = point(mid)
        e_pos, e_rot = ik.pose_error(q_mid, pos, yaw)
        if e_pos <= cfg.path_tol and e_rot <= cfg.path_rot_tol:
            i += 1
            continue
        if b - a < min_ds:
            return None
        res = ik.solve(pos, yaw, q_mid, offset=offset)
        if res.q is None:
            return None
        offset = res.offset
        ss.insert(i + 1, mid)
        qs.insert(i + 1, res.q)
        ms.insert(i + 1, ik.joint_rate(res.q, lin, yaw_rate))
    return LineTable(np.array(ss), np.array(qs), np.array(ms))


def plan_line(ik: SuctionIK, cfg: MotionConfig, start: np.ndarray, end: np.ndarray, yaw0: float, yaw1: float,
              speed: float, slow_last: float, q_start: np.ndarray) -> SegmentPlan | None:
    """Joint samples for a straight tip line (yaw interpolated), or None if unreachable; the
    last ``slow_last`` metres no faster than ``approach_speed`` (a guarded descent: fast
    through free space, braking to the approach speed where contact is expected, without
    stopping in between).  Timed by :func:`capmj.sim.timing.time_optimal`.  ``q_start`` are
    the joints at ``start``."""
    length = float(np.linalg.norm(end - start))
    # Treat wrist rotation as extra path length so pure rotations get time too.
    eff = max(length, cfg.yaw_path_length * abs(yaw1 - yaw0))
    slow = eff * min(1.0, slow_last / length) if slow_last > 0 and length > 0 else 0.0
    table = line_table(ik, cfg, start, end, yaw0, yaw1, q_start, eff)
    if table is None:
        return None
    if eff < 1e-9:  # a zero-length segment (a float-noise length): hold for one sample
        return SegmentPlan(table.at(np.array([0.0, 1.0])), cfg.ik_dt, np.array([0.0, 1.0]), eff)
    grid, split = timing_grid(eff, slow)
    first = table.derivative(grid)
    cap = np.where(grid >= split, cfg.approach_speed, speed) / eff if slow > 0 else np.full(len(grid), speed / eff)
    timing = time_optimal(grid, first, cap, cfg.accel / eff,
                          cfg.joint_speed * TIMING_SPEED_SHARE, cfg.joint_accel * TIMING_ACCEL_SHARE)
    if timing.slowdown > MAX_SLOWDOWN:
        return None  # would need a crawl: the joints cannot follow this line
    scale = 1.0
    for _ in range(RETIME_TRIES):
        if scale > MAX_SLOWDOWN:
            return None
        total = timing.total * scale
        n = max(1, int(np.ceil(total / cfg.ik_dt)))
        dt = total / n
        a = timing.at(np.arange(n + 1) * (dt / scale))
        a[0], a[-1] = 0.0, 1.0
        arr = table.at(a)
        if np.max(np.abs(np.diff(arr, axis=0)), initial=0.0) > MAX_JOINT_STEP:
            return None  # the IK branch flipped between samples (a wrist singularity)
        vel = np.diff(arr, axis=0) / dt
        acc = np.diff(vel, axis=0) / dt if len(vel) > 1 else np.zeros((1, 6))
        ratio = max(np.max(np.abs(vel)) / cfg.joint_speed, np.sqrt(np.max(np.abs(acc)) / cfg.joint_accel), 1.0)
        if ratio <= RETIME_RATIO_TOL:
            return SegmentPlan(arr, dt, a, eff)
        scale *= ratio * RETIME_MARGIN  # the grid let a limit slip between its points
    return SegmentPlan(arr, dt, a, eff)
