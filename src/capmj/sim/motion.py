"""Arm motion: Cartesian straight-line segments tracked by the Menagerie position servos, and the
Ravens pick-and-place primitive built from them.

Why this shape:
- Segments are straight lines of the suction tip.  The line is solved through :class:`SuctionIK`
  once, at path points chosen so that cubic Hermite interpolation in joint space between
  neighbours (with the joint rates from the Jacobian) keeps the tip within ``path_tol`` of the
  line (checked by forward kinematics at every interval's midpoint, where the interpolation error
  of a smooth path peaks).  The line is then timed, without solving it again, as fast as the
  tool's speed and acceleration caps and the joints' limits allow at each point
  (:func:`capmj.sim.timing.time_optimal`), and sampled every ``ik_dt`` seconds from that table.
  Solving every time sample instead (the first version) took ~220 IK solves per pick-and-place,
  more wall time than the physics; linear interpolation needed ~45; the Hermite table needs ~8.
- A move through several lines (:meth:`Motion.move_through`) plans them all before the arm moves
  and rounds each corner within ``blend``: the next line's reference is added to the last one's
  while it brakes, so the arm does not stop at the corner.
- The Menagerie servos are ``kp (ctrl - q) - kv qdot``: without feed-forward they lag a moving
  reference by ``kv/kp = 0.2 s``.  We send ``q_ref + (kv/kp) qdot_ref + (M qddot_ref + b) / kp``:
  the velocity term cancels that lag, the inertia term (the arm's mass-matrix block) the
  acceleration's, and ``b`` the load the arm's gravity compensation does not cover (the cup, a
  carried object; Coriolis at the segment start), which would otherwise make the tip sag.
- Every budget is in simulation steps, never wall-clock, so results do not depend on the machine.
- Failures are returned as :class:`PrimitiveResult` values, never raised.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Literal, Sequence

import numpy as np

from capmj.sim.ik import SuctionIK, arm_inertia_block
from capmj.sim.timing import time_optimal
from capmj.sim.world import World

Status = Literal["ok", "unreachable", "no_grip", "timeout", "held_nothing"]

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
leaves out, the path's curvature in joint space (``q'' ṡ²``).  Measured over 600 lines of the
primitives benchmark: at 100 % a third of the lines needed a retiming, at 90 % one in eleven, and
the lines took 0.3 % less time overall than at 100 %."""

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

EXECUTE_MAX_STEPS = 20000
"""Physics steps (40 s simulated) one segment may take at most, a guard against a runaway plan."""


@dataclass(frozen=True)
class MotionConfig:
    """Motion tuning of the arm.  ``yaw_path_length`` times the wrist turn (rad) counts as path
    length, so a pure wrist rotation gets time and IK points like a move of that length does; 0.1 m
    per rad turns the largest placement turn (45°) into ~8 cm.  ``retreat`` is how far the tip at
    least rises straight up after letting go (after a place it rises on to the next primitive's
    transit height, see :meth:`capmj.sim.primitives.Primitives.transit_height`), so the cup leaves
    the released object vertically before the next move goes sideways."""

    speed: float = 1.2            # m/s, free-space tip speed
    accel: float = 8.0            # m/s^2
    approach_speed: float = 0.25  # m/s for the last ``approach_gap`` before contact
    approach_gap: float = 0.02    # m
    overshoot: float = 0.03       # m searched beyond the expected contact height
    clearance: float = 0.06       # m between the lowest carried point and the highest object
    min_transit_z: float = 0.2    # m, tip height floor for transit
    joint_speed: float = 3.0      # rad/s (UR5e rating: 3.14)
    joint_accel: float = 20.0     # rad/s^2
    ik_dt: float = 0.02           # s between joint-space samples of a segment's timing
    path_step: float = 0.2        # m of path (``yaw_path_length`` per rad of wrist yaw) between IK solves before refinement
    yaw_path_length: float = 0.1  # m of path per rad of wrist yaw, for IK points and timing
    path_tol: float = 5e-4        # m tip error allowed by (Hermite) joint interpolation between IK solves
    path_rot_tol: float = 5e-3    # rad tool orientation error allowed the same way
    grip_dwell_steps: int = 10    # steps held after contact before lifting
    release_dwell_steps: int = 15
    settle_steps: int = 750       # max steps to let objects come to rest (1.5 s)
    settle_tol: float = 0.01      # m/s
    track_steps: int = 150        # max extra steps to converge at a segment end
    track_tol: float = 0.002      # m tip error accepted at a segment end
    retreat: float = 0.1          # m the tip rises after a release
    blend: float = 0.02           # m within which a corner of a multi-line move is rounded


@dataclass(frozen=True)
class PrimitiveResult:
    """Outcome of one pick-and-place; ``obj_id`` is what was gripped (None if nothing)."""

    ok: bool
    status: Status
    obj_id: int | None
    pick: tuple[float, float, float]
    place: tuple[float, float, float]
    final_pos: tuple[float, float, float] | None = None
    steps: int = 0
    sim_s: float = 0.0
    message: str = ""


@dataclass(frozen=True)
class _Plan:
    """Joint-space samples of one segment, ``dt`` seconds apart, tracked by :meth:`Motion.execute`;
    ``a`` is the path parameter (0 to 1) of each sample along a line of effective length ``extent``
    (None for a joint-space move), so a corner blend knows how far a sample is from the line's ends."""

    qs: np.ndarray   # (k, 6) joint samples
    dt: float        # seconds between samples
    a: np.ndarray | None = None
    extent: float = 0.0


@dataclass(frozen=True)
class _Table:
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


def _timing_grid(extent: float, slow: float) -> tuple[np.ndarray, float]:
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


class Motion:
    """Motion primitives over one :class:`World`."""

    def __init__(self, world: World, config: MotionConfig | None = None) -> None:
        self.world = world
        self.cfg = config or MotionConfig()
        m = world.model
        self.ik = SuctionIK(m, world.tip_site, world.arm_qpos, world.arm_dof)
        gain = m.actuator_gainprm[:6, 0]
        self._ff = -m.actuator_biasprm[:6, 2] / gain  # kv / kp per joint
        self._kp = gain

    # ------------------------------------------------------------------ segments
    def _line_table(self, start: np.ndarray, end: np.ndarray, yaw0: float, yaw1: float,
                    q_start: np.ndarray, extent: float) -> _Table | None:
        """IK solutions along the line, with their joint rates, such that cubic Hermite
        interpolation between neighbours stays within ``path_tol``/``path_rot_tol``; None if a
        point is unreachable or the IK branch flips (a wrist singularity).  ``extent`` is the
        line's effective length (rotation counted as in the timing).

        Hermite interpolation uses the joint rate dq/ds at each point (from the Jacobian), so its
        error shrinks with the fourth power of the spacing instead of the square: a line needs a
        few solves where linear interpolation needed one every few centimetres.  The interpolation
        error of both peaks at an interval's midpoint, which is where it is checked.
        """
        cfg, ik = self.cfg, self.ik
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
        return _Table(np.array(ss), np.array(qs), np.array(ms))

    def plan_line(self, start: np.ndarray, end: np.ndarray, yaw0: float, yaw1: float, speed: float,
                  slow_last: float = 0.0, q_start: np.ndarray | None = None) -> _Plan | None:
        """Joint samples for a straight tip line (yaw interpolated), or None if unreachable; the
        last ``slow_last`` metres no faster than ``approach_speed`` (a guarded descent: fast
        through free space, braking to the approach speed where contact is expected, without
        stopping in between).  Timed by :func:`capmj.sim.timing.time_optimal`.  ``q_start`` are
        the joints at ``start`` (default: the commanded ones)."""
        cfg = self.cfg
        length = float(np.linalg.norm(end - start))
        # Treat wrist rotation as extra path length so pure rotations get time too.
        eff = max(length, cfg.yaw_path_length * abs(yaw1 - yaw0))
        slow = eff * min(1.0, slow_last / length) if slow_last > 0 and length > 0 else 0.0
        q_prev = self.world.arm_ctrl() if q_start is None else q_start
        table = self._line_table(start, end, yaw0, yaw1, q_prev, eff)
        if table is None:
            return None
        if eff < 1e-9:  # a zero-length segment (a float-noise length): hold for one sample
            return _Plan(table.at(np.array([0.0, 1.0])), cfg.ik_dt, np.array([0.0, 1.0]), eff)
        grid, split = _timing_grid(eff, slow)
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
                return _Plan(arr, dt, a, eff)
            scale *= ratio * RETIME_MARGIN  # the grid let a limit slip between its points
        return _Plan(arr, dt, a, eff)

    def _reference(self, plan: _Plan, max_steps: int = EXECUTE_MAX_STEPS) -> tuple[np.ndarray, ...]:
        """The plan at every physics step: joint reference, its velocity and acceleration, and the
        path parameter (zeros for a joint-space move).  Interpolated from the samples, vectorised."""
        w = self.world
        ts = w.model.opt.timestep
        qs, dt = plan.qs, plan.dt
        n = len(qs) - 1
        total_steps = min(int(round(n * dt / ts)), max_steps)
        if n <= 0 or total_steps <= 0:
            empty = np.empty((0, 6))
            return empty, empty, empty, np.empty(0)
        t = (np.arange(total_steps) + 1) * ts
        i = np.minimum((t / dt).astype(int), n - 1)
        a = np.minimum((t - i * dt) / dt, 1.0)[:, None]
        vel = np.gradient(qs, dt, axis=0) if n > 1 else np.zeros_like(qs)
        vel[0] = vel[-1] = 0.0  # the profile starts and ends at rest
        acc = np.diff(vel, axis=0) / dt
        path = np.zeros(total_steps) if plan.a is None else plan.a[i] + a[:, 0] * (plan.a[i + 1] - plan.a[i])
        return qs[i] + a * (qs[i + 1] - qs[i]), vel[i] + a * (vel[i + 1] - vel[i]), acc[i], path

    def _track(self, q: np.ndarray, vel: np.ndarray, torque: np.ndarray, stop: Callable[[], bool] | None,
               stop_from: int = 0) -> tuple[bool, int]:
        """Step through a reference with feed-forward (see the module docstring; ``torque`` is the
        inertia term ``M qddot / kp``); ``stop`` is checked from step ``stop_from`` on.  Returns
        (stopped_early, steps)."""
        w = self.world
        if len(q):
            d = w.data  # the load beyond the arm's own gravity compensation: cup, carried object
            load = (d.qfrc_bias[w.arm_dof] - d.qfrc_gravcomp[w.arm_dof]) / self._kp
            ctrl = q + self._ff * vel + torque + load
        else:
            ctrl = np.empty((0, 6))
        steps, stopped = w.step_controls(ctrl[:stop_from])
        if not stopped:
            more, stopped = w.step_controls(ctrl[stop_from:], stop)
            steps += more
        return stopped, steps

    def _inertia_term(self, acc: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
        """``M qddot / kp`` for reference accelerations ``acc``, with the arm's inertia block
        (coupling included) at joints ``q``, or at the world's current state when None."""
        w = self.world
        inertia = arm_inertia_block(w.model, w.data, w.arm_dof) if q is None else self.ik.arm_inertia(q)
        return (acc @ inertia.T) / self._kp

    def execute(self, plan: _Plan, stop: Callable[[], bool] | None = None,
                max_steps: int = EXECUTE_MAX_STEPS) -> tuple[bool, int]:
        """Track a plan with velocity feed-forward; returns (stopped_early, steps).

        The whole control sequence is interpolated up front (vectorised) and stepped by
        :meth:`World.step_controls`, so the per-step Python work is one row copy, the physics step
        and the optional stop check.
        """
        q, vel, acc, _ = self._reference(plan, max_steps)
        stopped, steps = self._track(q, vel, self._inertia_term(acc), stop)
        self.world.set_arm_ctrl(self.world.arm_q() if stopped else plan.qs[-1])
        return stopped, steps

    def _blend_steps(self, path_a: np.ndarray, extent_a: float, path_b: np.ndarray, extent_b: float) -> int:
        """Physics steps by which line B may start before line A ends: both within ``blend`` of
        their shared corner (A's last steps, B's first), so the blended path stays within
        ``blend`` of the corner wherever it leaves the two lines."""
        r = self.cfg.blend
        if r <= 0 or extent_a <= 0 or extent_b <= 0:
            return 0
        tail = int(np.count_nonzero((1.0 - path_a) * extent_a <= r))
        head = int(np.count_nonzero(path_b * extent_b <= r))
        return min(tail, head, len(path_a) - 1)

    def converge(self, target: np.ndarray, stop: Callable[[], bool] | None = None) -> tuple[bool, int]:
        """Hold the last reference until the tip is within ``track_tol`` (bounded in steps)."""
        steps = 0
        for _ in range(self.cfg.track_steps):
            if np.linalg.norm(self.world.tip_pose()[0] - target) < self.cfg.track_tol:
                break
            self.world.step()
            steps += 1
            if stop is not None and stop():
                return True, steps
        return False, steps

    def unwind_wrist(self) -> int:
        """Turn wrist 3 by a full turn back towards zero when it is beyond ±π; returns steps.

        The tool pose is unchanged (a full turn), but IK continuity keeps later solutions near
        the current wrist angle, so without this the wrist would creep to its ±2π limit.
        """
        q = self.world.arm_ctrl()
        if abs(q[5]) <= np.pi:
            return 0
        goal = q.copy()
        goal[5] -= np.sign(q[5]) * 2 * np.pi
        duration = max(2 * np.pi / self.cfg.joint_speed, 2 * np.sqrt(2 * np.pi / self.cfg.joint_accel))
        n = max(2, int(np.ceil(duration / self.cfg.ik_dt)))
        s = np.linspace(0.0, 1.0, n + 1)
        s = s * s * (3 - 2 * s)  # smoothstep: zero speed at both ends
        qs = q + s[:, None] * (goal - q)
        return self.execute(_Plan(qs, duration / n))[1]

    def commanded_yaw(self) -> float:
        """Tool yaw of the currently commanded joints (read from the arm, never remembered)."""
        self.ik.tip_position(self.world.arm_ctrl())
        rot = self.ik.data.site_xmat[self.ik.site].reshape(3, 3)
        return float(np.arctan2(rot[1, 0], rot[0, 0]))

    def move_to(self, pos: np.ndarray, yaw: float, speed: float | None = None,
                stop: Callable[[], bool] | None = None, slow_last: float = 0.0) -> tuple[str, int]:
        """Move the tip in a straight line; returns ("ok" | "stopped" | "unreachable", steps).
        The last ``slow_last`` metres run at ``approach_speed`` without stopping first (a guarded
        descent: fast through free space, slow where contact is expected)."""
        return self.move_through([(pos, yaw)], speed, stop, slow_last)[:2]

    def move_through(self, points: Sequence[tuple[np.ndarray, float]], speed: float | None = None,
                     stop: Callable[[], bool] | None = None, slow_last: float = 0.0) -> tuple[str, int, int]:
        """Move the tip along straight lines through each ``(pos, yaw)`` in turn, rounding each
        corner within ``blend`` (the next line starts while the last one brakes, as a UR
        controller's blend radius does) instead of stopping there.  ``stop`` and ``slow_last``
        concern the last line only.  Returns (status, steps, index of the line that could not be
        planned or -1); every line is planned before the arm moves, so "unreachable" moves nothing.

        The start pose is read from the commanded joints, so a state restore (re-plan) or a
        stopped move can never leave a stale start yaw behind.
        """
        q = self.world.arm_ctrl()
        start, yaw_prev = self.ik.tip_position(q), self.commanded_yaw()
        plans = []
        for k, (pos, yaw) in enumerate(points):
            pos = np.asarray(pos, float)
            yaw0 = yaw + ((yaw_prev - yaw + np.pi) % (2 * np.pi) - np.pi)  # same angle, nearest the goal
            last = k == len(points) - 1
            plan = self.plan_line(start, pos, yaw0, yaw, speed or self.cfg.speed, slow_last if last else 0.0, q)
            if plan is None:
                return "unreachable", 0, k
            plans.append(plan)
            start, q, yaw_prev = pos, plan.qs[-1], yaw
        # Each line's inertia term uses the arm's inertia where that line starts; a blend adds the
        # two lines' references, velocities and inertia terms over the overlap.
        ref_q, ref_v, acc, path = self._reference(plans[0])
        ref_t = self._inertia_term(acc)
        stop_from = 0
        for before, plan in zip(plans, plans[1:]):
            q_b, v_b, a_b, path_b = self._reference(plan)
            t_b = self._inertia_term(a_b, plan.qs[0])
            o = self._blend_steps(path, before.extent, path_b, plan.extent)
            if o:
                ref_q[-o:] += q_b[:o] - plan.qs[0]
                ref_v[-o:] += v_b[:o]
                ref_t[-o:] += t_b[:o]
            stop_from = len(ref_q) - o
            ref_q, ref_v = np.concatenate([ref_q, q_b[o:]]), np.concatenate([ref_v, v_b[o:]])
            ref_t, path = np.concatenate([ref_t, t_b[o:]]), path_b
        stopped, steps = self._track(ref_q, ref_v, ref_t, stop, stop_from)
        if stopped:
            self.world.set_arm_ctrl(self.world.arm_q())
            return "stopped", steps, -1
        self.world.set_arm_ctrl(plans[-1].qs[-1])
        stopped, more = self.converge(np.asarray(points[-1][0], float), stop)
        return ("stopped" if stopped else "ok"), steps + more, -1
