"""Arm motion: Cartesian straight-line segments tracked by the Menagerie position servos, the
moves the Ravens pick-and-place primitive (:mod:`capmj.sim.primitives`) is built from.

Why this shape:
- Segments are straight lines of the suction tip, planned by :mod:`capmj.sim.line_plan` (IK at a
  few points, Hermite interpolation in joint space, time-optimal timing).
- A move through several lines (:meth:`Motion.move_through`) plans them all before the arm moves
  and rounds each corner within ``blend``: the next line's reference is added to the last one's
  while it brakes, so the arm does not stop at the corner.
- The Menagerie servos are ``kp (ctrl - q) - kv qdot``: without feed-forward they lag a moving
  reference by ``kv/kp = 0.2 s``.  We send ``q_ref + (kv/kp) qdot_ref + (M qddot_ref + b) / kp``:
  the velocity term cancels that lag, the inertia term (the arm's mass-matrix block) the
  acceleration's, and ``b`` the load the arm's gravity compensation does not cover (the cup, a
  carried object; Coriolis at the segment start), which would otherwise make the tip sag.
- Every move is checked for collisions before it runs (:meth:`Motion.clear_legs`, on MuJoCo's own
  collision detection, :mod:`capmj.sim.collision`): a leg that is not clear is replaced by a
  joint-space path around the obstacle (:mod:`capmj.sim.planner`), and a move with no clear path
  raises :class:`~capmj.errors.MotionPlanningError` before anything moves (``plan_collisions`` off:
  the straight legs alone, unchecked).
- Every budget is in simulation steps, never wall-clock, so results do not depend on the machine.
- An unreachable line is a status, never raised; the pick-and-place primitive returns every failure,
  a missing path included, as a :class:`PrimitiveResult`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Literal, Sequence

import numpy as np

from capmj.errors import MotionPlanningError
from capmj.sim.collision import CHECK_STEP, TABLE, Allowance, CollisionChecker
from capmj.sim.ik import SuctionIK, arm_inertia_block, tool_rotation
from capmj.sim.line_plan import SegmentPlan, plan_line
from capmj.sim.motion_config import MotionConfig
from capmj.sim.planner import plan_joint_path, query_seed
from capmj.sim.world import World

Status = Literal["ok", "unreachable", "no_grip", "timeout", "held_nothing", "no_path"]

Waypoints = tuple[tuple[float, float, float], ...]
"""A polyline of tip positions (m)."""

EXECUTE_MAX_STEPS = 20000
"""Physics steps (40 s simulated) one segment may take at most, a guard against a runaway plan."""


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
    planned: tuple[Waypoints, ...] = ()
    """Tip polylines of the moves that were planned around an obstacle (none when every straight
    move was clear), for drawing."""


@dataclass(frozen=True)
class PathRecord:
    """One move as executed: its joint waypoints (rows) and the tip at each, and whether it was
    planned around an obstacle (else straight tool lines or a straight joint move)."""

    joints: np.ndarray
    tip: Waypoints
    planned: bool


class Motion:
    """Motion primitives over one :class:`World`."""

    def __init__(self, world: World, config: MotionConfig | None = None, seed: int = 0) -> None:
        self.world = world
        self.cfg = config or MotionConfig()
        self.seed = seed
        m = world.model
        self.ik = SuctionIK(m, world.tip_site, world.arm_qpos, world.arm_dof)
        gain = m.actuator_gainprm[:6, 0]
        self._ff = -m.actuator_biasprm[:6, 2] / gain  # kv / kp per joint
        self._kp = gain
        self._checker: CollisionChecker | None = None
        self.paths: list[PathRecord] = []
        """Every move made so far, in order (see :class:`PathRecord`)."""
        self.planning_s = 0.0
        """Wall seconds spent checking and planning paths so far (for the benchmark)."""

    @property
    def moves_made(self) -> int:
        """How many moves :attr:`paths` holds: a mark for :meth:`planned_tips`."""
        return len(self.paths)

    def planned_tips(self, since: int = 0) -> tuple[Waypoints, ...]:
        """The tool paths of the moves after mark ``since`` that were planned around an obstacle."""
        return tuple(p.tip for p in self.paths[since:] if p.planned)

    @property
    def checker(self) -> CollisionChecker:
        """The collision checker of this world (made on first use)."""
        if self._checker is None:
            self._checker = CollisionChecker(self.world, self.cfg.plan_clearance)
        return self._checker

    # ------------------------------------------------------------------ segments
    def plan_line(self, start: np.ndarray, end: np.ndarray, yaw0: float, yaw1: float, speed: float,
                  slow_last: float = 0.0, q_start: np.ndarray | None = None) -> SegmentPlan | None:
        """Joint samples for a straight tip line (yaw interpolated), or None if unreachable; the
        last ``slow_last`` metres no faster than ``approach_speed`` (:func:`capmj.sim.line_plan.
        plan_line`).  ``q_start`` are the joints at ``start`` (default: the commanded ones)."""
        q_prev = self.world.arm_ctrl() if q_start is None else q_start
        return plan_line(self.ik, self.cfg, start, end, yaw0, yaw1, speed, slow_last, q_prev)

    def _reference(self, plan: SegmentPlan, max_steps: int = EXECUTE_MAX_STEPS) -> tuple[np.ndarray, ...]:
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

    def execute(self, plan: SegmentPlan, stop: Callable[[], bool] | None = None,
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
        return self.execute(SegmentPlan(qs, duration / n))[1]

    def commanded_yaw(self) -> float:
        """Tool yaw of the currently commanded joints (read from the arm, never remembered)."""
        self.ik.tip_position(self.world.arm_ctrl())
        rot = self.ik.data.site_xmat[self.ik.site].reshape(3, 3)
        return float(np.arctan2(rot[1, 0], rot[0, 0]))

    def move_to(self, pos: np.ndarray, yaw: float, speed: float | None = None,
                stop: Callable[[], bool] | None = None, slow_last: float = 0.0,
                guarded: bool | None = None) -> tuple[str, int]:
        """Move the tip in a straight line; returns ("ok" | "stopped" | "unreachable", steps).
        The last ``slow_last`` metres run at ``approach_speed`` without stopping first (a guarded
        descent: fast through free space, slow where contact is expected; ``guarded``: see
        :meth:`move_through`)."""
        return self.move_through([(pos, yaw)], speed, stop, slow_last, guarded=guarded)[:2]

    def move_through(self, points: Sequence[tuple[np.ndarray, float]], speed: float | None = None,
                     stop: Callable[[], bool] | None = None, slow_last: float = 0.0,
                     contact_before: float = 0.0, guarded: bool | None = None) -> tuple[str, int, int]:
        """Move the tip along straight lines through each ``(pos, yaw)`` in turn, rounding each
        corner within ``blend`` (the next line starts while the last one brakes, as a UR
        controller's blend radius does) instead of stopping there.  ``stop`` and ``slow_last``
        concern the last line only.  Returns (status, steps, index of the line that could not be
        planned or -1); every line is planned before the arm moves, so "unreachable" moves nothing.

        With ``plan_collisions`` every line is checked for collisions first (:meth:`clear_legs`):
        one that is not clear is replaced by a joint-space path around the obstacle, and
        :class:`~capmj.errors.MotionPlanningError` is raised, before anything moves, when there is
        none.  A ``guarded`` last line (a descent that ``stop`` ends at its contact; by default
        any move with a ``stop``) may end touching what is under its end; ``contact_before`` is
        how far before its end the contact is expected (a descent's overshoot), the part beyond
        which is not checked for the arm's links.  ``guarded=False`` with a ``stop`` (a watch for
        any contact) keeps every check and lets the last line be planned around an obstacle.

        The start pose is read from the commanded joints, so a state restore (re-plan) or a
        stopped move can never leave a stale start yaw behind.
        """
        plans = self.plan_lines(points, speed, slow_last)
        if isinstance(plans, int):
            return "unreachable", 0, plans
        plans = self.clear_legs(plans, guarded=stop is not None if guarded is None else guarded,
                                contact_before=contact_before)
        status, steps = self.run_legs(plans, np.asarray(points[-1][0], float), stop)
        return status, steps, -1

    def plan_lines(self, points: Sequence[tuple[np.ndarray, float]], speed: float | None = None,
                   slow_last: float = 0.0, q_start: np.ndarray | None = None) -> list[SegmentPlan] | int:
        """The straight tool lines of :meth:`move_through` from joints ``q_start`` (default: the
        commanded ones), unchecked; or the index of the first line that cannot be planned."""
        q = self.world.arm_ctrl() if q_start is None else np.asarray(q_start, float)
        start = self.ik.tip_position(q)
        rot = self.ik.data.site_xmat[self.ik.site].reshape(3, 3)
        yaw_prev = float(np.arctan2(rot[1, 0], rot[0, 0]))
        plans = []
        for k, (pos, yaw) in enumerate(points):
            pos = np.asarray(pos, float)
            yaw0 = yaw + ((yaw_prev - yaw + np.pi) % (2 * np.pi) - np.pi)  # same angle, nearest the goal
            last = k == len(points) - 1
            plan = self.plan_line(start, pos, yaw0, yaw, speed or self.cfg.speed, slow_last if last else 0.0, q)
            if plan is None:
                return k
            plans.append(plan)
            start, q, yaw_prev = pos, plan.qs[-1], yaw
        return plans

    def run_legs(self, plans: Sequence[SegmentPlan], target: np.ndarray,
                 stop: Callable[[], bool] | None = None) -> tuple[str, int]:
        """Track consecutive legs as one move (corners between two tool lines rounded within
        ``blend``; a joint-space leg starts and ends at rest), then converge on the tip position
        ``target``; ``stop`` is checked on the last leg.  Returns ("ok" | "stopped", steps).  The
        legs are run as given: check them first (:meth:`clear_legs`)."""
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
            return "stopped", steps
        self.world.set_arm_ctrl(plans[-1].qs[-1])
        stopped, more = self.converge(target, stop)
        return ("stopped" if stopped else "ok"), steps + more

    def branches(self, pos: np.ndarray, yaw: float) -> list[np.ndarray]:
        """Every IK branch (shoulder, elbow, wrist) reaching ``pos`` pointing down with ``yaw``
        within the joint limits, refined on the model, nearest the commanded joints first: other
        arm postures for the same tool pose, whose links stand elsewhere."""
        q_now = self.world.arm_ctrl()
        target = np.eye(4)
        target[:3, :3] = tool_rotation(yaw)
        target[:3, 3] = pos
        out: list[np.ndarray] = []
        for sol in self.ik._solver.inverse_kinematics_with_tcp(target, self.ik._tcp):
            q = np.asarray(sol, float)
            if not np.all(np.isfinite(q)):
                continue
            q = q_now + (q - q_now + np.pi) % (2 * np.pi) - np.pi  # each joint's turn nearest the current one
            res = self.ik.solve(pos, yaw, q)
            if res.q is not None and not any(np.allclose(res.q, o, atol=1e-3) for o in out):
                out.append(res.q)
        return sorted(out, key=lambda q: float(np.abs(q - q_now).max()))

    # ------------------------------------------------------------------ planned moves
    def move_joints(self, q_goal: np.ndarray, stop: Callable[[], bool] | None = None) -> tuple[str, int]:
        """Move the arm to joints ``q_goal``: straight in joint space when that is clear, else on a
        path planned around the obstacle (:meth:`clear_legs`).  Returns ("ok" | "stopped" |
        "unreachable", steps); "unreachable" (beyond a joint limit) moves nothing.  Raises
        :class:`~capmj.errors.MotionPlanningError` before moving when no clear path exists."""
        q_goal = np.asarray(q_goal, float)
        if q_goal.shape != (6,) or not np.all(np.isfinite(q_goal)) \
                or np.any(q_goal < self.ik.lo) or np.any(q_goal > self.ik.hi):
            return "unreachable", 0
        plan = self.joint_plan(np.array([self.world.arm_ctrl(), q_goal]))
        plan = self.clear_legs([plan])[0]
        stopped, steps = self.execute(plan, stop)
        if stopped:
            return "stopped", steps
        stopped, more = self.converge(self.ik.tip_position(q_goal), stop)
        return ("stopped" if stopped else "ok"), steps + more

    def move_to_pose(self, pos: np.ndarray, yaw: float, stop: Callable[[], bool] | None = None,
                     speed: float | None = None) -> tuple[str, int]:
        """Move the tip to ``pos`` pointing down with tool ``yaw``, by the most direct clear way: a
        straight tool line when it is reachable (planned around an obstacle when it is not clear,
        as :meth:`move_through`), else a joint-space move (:meth:`move_joints`) to the arm's
        postures for that pose (:meth:`branches`), nearest first, the first with a clear path.
        Returns ("ok" | "stopped" | "unreachable", steps); "unreachable" (no IK solution) moves
        nothing.  Raises the first :class:`~capmj.errors.MotionPlanningError` before moving when
        no posture has a clear path."""
        pos = np.asarray(pos, float)
        first: MotionPlanningError | None = None
        try:
            status, steps, _ = self.move_through([(pos, yaw)], speed, stop, guarded=False)  # nothing may touch
            if status != "unreachable":
                return status, steps
        except MotionPlanningError as exc:
            first = exc
        postures = self.branches(pos, yaw)
        if not postures:
            return "unreachable", 0
        for q in postures:  # the arm's other postures for the same tool pose, nearest first
            try:
                return self.move_joints(q, stop)
            except MotionPlanningError as exc:
                first = first or exc
        assert first is not None
        raise first

    def joint_plan(self, waypoints: np.ndarray) -> SegmentPlan:
        """A timed joint-space move through ``waypoints`` (rows), straight in joint space between
        them and at rest at each: every edge a smoothstep within the joint speed and acceleration
        limits (peak speed 1.5 d / T, peak acceleration 6 d / T^2 for the largest joint change d)."""
        cfg = self.cfg
        wp = np.asarray(waypoints, float)
        parts = [wp[:1]]
        for a, b in zip(wp, wp[1:]):
            d = float(np.max(np.abs(b - a)))
            duration = max(1.5 * d / cfg.joint_speed, float(np.sqrt(6.0 * d / cfg.joint_accel)), cfg.ik_dt)
            n = max(1, int(np.ceil(duration / cfg.ik_dt)))
            s = np.linspace(0.0, 1.0, n + 1)[1:]
            s = s * s * (3 - 2 * s)
            parts.append(a + s[:, None] * (b - a))
        return SegmentPlan(np.concatenate(parts), cfg.ik_dt)

    def clear_legs(self, plans: list[SegmentPlan], guarded: bool = False,
                   contact_before: float = 0.0) -> list[SegmentPlan]:
        """The legs of one move (consecutive plans, each starting where the last ends), each
        checked for collisions densely (:class:`~capmj.sim.collision.CollisionChecker`) and, when
        not clear, replaced by a joint-space path around the obstacle (:mod:`capmj.sim.planner`).

        What may touch: the pairs touching where the move starts (first leg only), and for a
        ``guarded`` move (one that stops at contact) on its last leg the cup and the carried
        object may touch what they touch where that leg ends (the object being picked, the
        surface being placed on) and the table, and pass anything else closer than the
        clearance (a placement next to its neighbours) without pressing into it.  That last leg
        is never replaced (its end is the contact the move is for), and it is checked only up to
        ``contact_before`` metres of path before its end, where the contact is expected (a
        guarded move stops there; the rest is the margin it may go on by when the surface is
        lower).  Raises :class:`~capmj.errors.MotionPlanningError` when a leg is not clear and
        cannot be replaced.  Records each leg in :attr:`paths`.  With ``plan_collisions`` off
        the legs are returned unchecked (and recorded).
        """
        if not self.cfg.plan_collisions:
            for plan in plans:
                self._record(plan, planned=False)
            return plans
        t0 = time.perf_counter()
        try:
            return self._clear_legs(plans, guarded, contact_before)
        finally:
            self.planning_s += time.perf_counter() - t0

    def _clear_legs(self, plans: list[SegmentPlan], guarded: bool, contact_before: float) -> list[SegmentPlan]:
        chk = self.checker
        chk.sync()
        start = Allowance(pairs=chk.touching(plans[0].qs[0]))
        out: list[SegmentPlan] = []
        records: list[tuple[SegmentPlan, bool]] = []
        for i, plan in enumerate(plans):
            allow = start if i == 0 else Allowance()
            last_guarded = guarded and i == len(plans) - 1
            if last_guarded:
                allow = allow | Allowance(tool_may_touch=chk.tool_owners(plan.qs[-1]) | {TABLE}, tool_near=True)
            hit = chk.path_collision(_until_contact(plan, contact_before) if last_guarded else plan.qs, allow)
            if hit is None:
                out.append(plan)
                records.append((plan, False))
                continue
            where = self.ik.tip_position(plan.qs[-1])
            target = f"({where[0]:.3f}, {where[1]:.3f}, {where[2]:.3f})"
            if last_guarded:
                raise MotionPlanningError(f"no collision-free path to {target}: {hit[1]}", status="no_path")
            at_goal = chk.collision(plan.qs[-1], allow)
            if at_goal is not None:
                raise MotionPlanningError(f"no collision-free path to {target}: at the target itself {at_goal}",
                                          status="no_path")
            around = self._plan_around(plan.qs[0], plan.qs[-1], allow)
            if around is None:
                raise MotionPlanningError(f"no collision-free path to {target}: {hit[1]} on the straight way, and "
                                          "no way around it was found", status="no_path")
            joint = self.joint_plan(around)
            out.append(joint)
            records.append((joint, True))
        for plan, planned in records:
            self._record(plan, planned)
        return out

    def _plan_around(self, q_a: np.ndarray, q_b: np.ndarray, allow: Allowance) -> np.ndarray | None:
        """Joint waypoints from ``q_a`` to ``q_b`` clear under ``allow``, or None."""
        chk = self.checker

        def valid(q: np.ndarray) -> bool:
            return chk.collision(q, allow) is None

        def edges_clear(waypoints: np.ndarray) -> bool:
            return chk.path_collision(waypoints, allow) is None

        seed = query_seed(self.seed, q_a, q_b, self.world.data.qpos)
        path = plan_joint_path(valid, edges_clear, q_a, q_b, self.ik.lo, self.ik.hi, seed, CHECK_STEP,
                               self.cfg.plan_max_checks)
        return None if path is None else path.waypoints

    def _record(self, plan: SegmentPlan, planned: bool) -> None:
        """Keep one leg in :attr:`paths` (its tip drawn at every sample when planned, else its ends)."""
        qs = plan.qs if planned else plan.qs[[0, -1]]
        tip = tuple(tuple(float(v) for v in self.ik.tip_position(q)) for q in qs)
        self.paths.append(PathRecord(qs.copy(), tip, planned))  # type: ignore[arg-type]


def _until_contact(plan: SegmentPlan, before_end: float) -> np.ndarray:
    """The joint samples of a line up to ``before_end`` metres of path before its end (where a
    guarded move expects its contact); all of them for a joint-space plan or no margin."""
    if plan.a is None or before_end <= 0 or plan.extent <= before_end:
        return plan.qs
    cut = 1.0 - before_end / plan.extent
    k = int(np.searchsorted(plan.a, cut, side="right"))  # samples at or before the cut
    if k >= len(plan.qs):
        return plan.qs
    a0, a1 = plan.a[k - 1], plan.a[k]
    f = 0.0 if a1 <= a0 else (cut - a0) / (a1 - a0)
    return np.concatenate([plan.qs[:k], (plan.qs[k - 1] + f * (plan.qs[k] - plan.qs[k - 1]))[None]])
