"""The robot driver under the low-level planner API (``--api low``): moves, suction, budgets, records.

:class:`RobotDriver` is what :class:`~capmj.agents.api.low_level.LowLevelFunctions` acts through.
It runs the arm in real physics with the sim's own motion layer (:class:`~capmj.sim.motion.Motion`):
planned moves (:meth:`RobotDriver.move_planned`, :meth:`RobotDriver.move_joints`) are collision-checked
and planned around obstacles there; straight moves (:meth:`RobotDriver.move_lines`,
:meth:`RobotDriver.move_until_contact`) are tip lines planned on IK before the arm moves and
executed as asked.  On top it adds what a robot driver adds:

* **Contact watch.**  Every move is watched step by step for a *new* contact (one that did not
  exist when the move started, :class:`~capmj.sim.contact_watch.ContactWatch`) of an arm link, the
  suction cup or the carried object with the table or an object.  A guarded move (:meth:`RobotDriver.move_until_contact`) stops at the first
  contact of the tool (the cup, or the carried object when one is held) and reports it; any other
  new contact stops the arm where it is and raises :class:`~capmj.errors.CollisionDetected`.
* **Refusals before motion.**  A target below the table top, out of reach or beyond a joint limit
  raises :class:`~capmj.errors.UnreachablePose` before the arm moves.
* **Budgets and records.**  Each move counts as one primitive of the episode context against
  ``Budget.max_primitives`` × :data:`MOVES_PER_PRIMITIVE` (and the attempt's simulation steps) and
  is sent to the recorder as a primitive from the tip's start to its end.
* **Perception.**  Under ``--perception rgbd`` the scene is perceived again after every release of
  the suction, the tracker told which perceived object was carried where.

The tool always points straight down; a tool pose is a position and a yaw about z.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Protocol, Sequence

import numpy as np

from capmj.agents.api.interface import PlannerInterface
from capmj.errors import CollisionDetected, UnreachablePose
from capmj.sim.contact_watch import CUP, LINK, TABLE, ContactWatch
from capmj.sim.line_plan import SegmentPlan
from capmj.sim.motion import Motion
from capmj.sim.pose import mat_yaw
from capmj.sim.robot import HOME_QPOS
from capmj.sim.world import World

MOVES_PER_PRIMITIVE = 8
"""A pick-and-place is about five moves at this level (over, down, over, down, up): the low-level
move budget of an attempt is ``Budget.max_primitives`` times this."""

TABLE_Z = 0.0
"""m: the table top; no move target of the tip may lie below it (a guarded move's may, down to
:data:`CONTACT_DEPTH` below, since it stops on contact)."""

CONTACT_DEPTH = 0.05
"""m below the table top a guarded move may aim at (it stops where the tool meets something)."""


class _Perceiving(Protocol):
    """The part of :class:`~capmj.agents.api.perceived.PerceivedScene` the driver uses."""

    def refresh(self, moved: dict[int, tuple[float, float, float]]) -> None: ...


class RobotDriver:
    """The arm and suction of one episode as a robot driver offers them (module docstring).

    ``name_of`` names an object the robot touched (by its simulator id) for an error message, or
    returns None where the API must not name it (perceived mode)."""

    def __init__(self, api: PlannerInterface, name_of: Callable[[int], str | None]) -> None:
        self._api = api
        self._name_of = name_of
        self._gripped: tuple[int, np.ndarray, np.ndarray] | None = None
        """Perceived mode: (the perceived object gripped, its centre then, the tip then)."""
        self._recent: set[tuple[int, int]] = set()
        """Contacts the next move may part from and touch again: those the last move ended with,
        and the cup on the object the suction has just let go."""

    # ------------------------------------------------------------------ reading
    @property
    def world(self) -> World:
        """The simulated robot's world (never the perceived scene)."""
        return self._api.ctx.world

    @property
    def motion(self) -> Motion:
        return self._api.ctx.arm.motion  # read each time: a reset builds a new arm

    def tool_pose(self) -> tuple[np.ndarray, float]:
        """The suction tip's position and yaw (where it is, not where it is commanded)."""
        pos, rot = self.world.tip_pose()
        return pos, mat_yaw(rot)

    def joints(self) -> np.ndarray:
        return self.world.arm_q()

    def ik(self, pos: np.ndarray, yaw: float, q_near: np.ndarray | None = None) -> np.ndarray:
        """Joints putting the tip at ``pos`` pointing down with ``yaw``, nearest ``q_near`` (default
        the commanded joints); :class:`UnreachablePose` when there are none."""
        self._check_height(pos, TABLE_Z)
        near = self.world.arm_ctrl() if q_near is None else q_near
        res = self.motion.ik.solve(pos, yaw, near)
        if res.q is None:
            raise UnreachablePose(f"no IK solution for the tool at {_fmt(pos)} with yaw {yaw:.3f} rad: out of reach "
                                  "or beyond a joint limit", status="unreachable")
        return res.q

    def holding(self) -> bool:
        return self.world.suction.held is not None

    # ------------------------------------------------------------------ moves
    def move_lines(self, fn: str, points: Sequence[tuple[np.ndarray, float]], speed: float | None = None) -> None:
        """Straight tip lines through ``points`` ((position, yaw) each), exactly as asked (never
        planned around anything), every line planned on IK before the arm moves; a new contact
        on the way stops the arm and raises :class:`CollisionDetected`."""
        for pos, _ in points:
            self._check_height(pos, TABLE_Z)
        plans = self._line_plans(points, speed)
        self._move(fn, lambda watch: self._run_lines(plans, points, watch), guarded=False)

    def move_until_contact(self, fn: str, pos: np.ndarray, yaw: float, speed: float) -> bool:
        """A straight tip line towards ``pos`` that stops at the tool's first contact; whether it
        touched (False: it reached ``pos`` touching nothing)."""
        self._check_height(pos, TABLE_Z - CONTACT_DEPTH)
        plans = self._line_plans([(pos, yaw)], speed)
        return self._move(fn, lambda watch: self._run_lines(plans, [(pos, yaw)], watch), guarded=True)

    def move_planned(self, fn: str, pos: np.ndarray, yaw: float) -> None:
        """The tool to ``pos`` on a path clear of everything: up to the height that clears every
        object (the carried object's hang included), across, straight down, each leg checked by
        the sim's collision checker and planned around what is in its way
        (:meth:`~capmj.sim.motion.Motion.move_through`); where those legs are out of reach, the
        sim's own planned move to the pose (:meth:`~capmj.sim.motion.Motion.move_to_pose`).  No
        clear path raises :class:`~capmj.errors.MotionPlanningError` before the arm moves."""
        self._check_height(pos, TABLE_Z)
        w = self.world
        held = w.suction.held
        tip = w.tip_pose()[0]
        hang = 0.0 if held is None else max(0.0, float(tip[2] - w.aabb(held)[0][2]))
        transit = max(self._api.ctx.arm.transit_height(exclude=held, hang=hang), float(pos[2]))
        legs: list[tuple[np.ndarray, float]] = []
        if tip[2] < transit - 1e-3:
            legs.append((np.array([tip[0], tip[1], transit]), yaw))
        if math.hypot(pos[0] - tip[0], pos[1] - tip[1]) > 1e-4:
            legs.append((np.array([pos[0], pos[1], transit]), yaw))
        legs.append((np.asarray(pos, float), yaw))
        try:
            self._line_plans(legs, None)
        except UnreachablePose:
            legs = []
        if not legs:
            self.ik(pos, yaw)  # UnreachablePose when the pose itself is out of reach

        def run(watch: ContactWatch) -> str:
            m = self.motion
            if legs:
                return m.move_through(legs, stop=watch.new_contact, guarded=False)[0]  # watched, not guarded: nothing may touch
            return m.move_to_pose(pos, yaw, stop=watch.new_contact)[0]

        self._move(fn, run, guarded=False)

    def move_joints(self, fn: str, q: np.ndarray) -> None:
        """A joint-space move to ``q``: straight in joint space when that is clear, else planned
        around what is in the way (:meth:`~capmj.sim.motion.Motion.move_joints`)."""
        ik = self.motion.ik
        bad = [i for i in range(6) if not ik.lo[i] <= q[i] <= ik.hi[i]]
        if bad:
            raise UnreachablePose(f"joints {_fmt(q)}: joint(s) {bad} beyond their limits "
                                  f"{[(round(float(ik.lo[i]), 3), round(float(ik.hi[i]), 3)) for i in bad]}",
                                  status="unreachable")
        self._check_height(ik.tip_position(q), TABLE_Z)
        self._move(fn, lambda watch: self.motion.move_joints(q, stop=watch.new_contact)[0], guarded=False)

    def home(self, fn: str) -> None:
        self.move_joints(fn, np.asarray(HOME_QPOS, float))

    def _check_height(self, pos: np.ndarray, floor: float) -> None:
        if not np.all(np.isfinite(pos)):
            raise ValueError(f"position {_fmt(pos)} is not finite")
        if pos[2] < floor:
            what = "the table top (z = 0)" if floor == TABLE_Z else f"{-floor:.2f} m below the table top"
            raise UnreachablePose(f"target {_fmt(pos)} is below {what}: the tool would go into the table "
                                  "(move_until_contact descends onto a surface and stops there)",
                                  status="below_table")

    def _line_plans(self, points: Sequence[tuple[np.ndarray, float]], speed: float | None) -> list[SegmentPlan]:
        """Every line planned on IK from the commanded joints before anything moves:
        :class:`UnreachablePose` names the first waypoint the tool cannot reach in a straight line."""
        m = self.motion
        q = self.world.arm_ctrl()
        start, yaw_prev = m.ik.tip_position(q), m.commanded_yaw()
        plans = []
        for k, (pos, yaw) in enumerate(points):
            yaw0 = yaw + ((yaw_prev - yaw + math.pi) % (2 * math.pi) - math.pi)  # same angle, nearest the goal
            plan = m.plan_line(start, pos, yaw0, yaw, speed or m.cfg.speed, 0.0, q)
            if plan is None:
                where = f"waypoint {k} " if len(points) > 1 else ""
                raise UnreachablePose(f"{where}{_fmt(pos)} (yaw {yaw:.3f} rad) cannot be reached in a straight line "
                                      f"from {_fmt(start)}: out of reach or beyond a joint limit on the way",
                                      status="unreachable")
            plans.append(plan)
            start, q, yaw_prev = pos, plan.qs[-1], yaw
        return plans

    def _run_lines(self, plans: list[SegmentPlan], points: Sequence[tuple[np.ndarray, float]],
                   watch: ContactWatch) -> str:
        """Track the lines one after the other (each to rest), stopping at a new contact."""
        m = self.motion
        for plan, (pos, _) in zip(plans, points):
            if m.execute(plan, stop=watch.new_contact)[0] or m.converge(pos, stop=watch.new_contact)[0]:
                return "stopped"
        return "ok"

    def _move(self, fn: str, run: Callable[[ContactWatch], str], guarded: bool) -> bool:
        """One budgeted, recorded move; whether it ended on the tool's contact (guarded moves)."""
        ctx = self._api.ctx
        ctx.check_budget(ctx.budget.max_primitives * MOVES_PER_PRIMITIVE, "low-level moves")
        w = self.world
        start, steps0, t0 = w.tip_pose()[0], w.steps, w.time
        motion = self.motion
        mark = motion.moves_made
        watch = ContactWatch(w, self._recent)
        try:
            status = run(watch)
        finally:
            self._recent = watch.ending()
        touched = status == "stopped" and (guarded and watch.tool_contact())
        collided = status == "stopped" and not touched
        end = w.tip_pose()[0]
        message = self._collision_text(fn, watch, end) if collided else fn  # the primitive log line names the move
        if status not in ("ok", "stopped"):
            message = f"{fn}: {status}"
        shown = "collision" if collided else "contact" if touched else status
        ctx.count_primitive({
            "ok": not collided and status in ("ok", "stopped"), "status": shown,
            "kind": "move", "fn": fn, "obj_id": w.suction.held, "pick": tuple(float(v) for v in start),
            "place": tuple(float(v) for v in end), "final_pos": None, "steps": w.steps - steps0,
            "sim_s": w.time - t0, "message": message, "contact": touched,
            "planned": motion.planned_tips(mark),  # drawn as lines in the .rrd
        })
        if collided:
            raise CollisionDetected(message, status="collision")
        if status not in ("ok", "stopped"):
            raise UnreachablePose(message, status="unreachable")
        return touched

    def _collision_text(self, fn: str, watch: ContactWatch, at: np.ndarray) -> str:
        own, other = watch.hit if watch.hit is not None else (LINK, TABLE)
        who = {CUP: "the suction cup", LINK: "an arm link"}.get(own, "the carried object")
        if other == TABLE:
            what = "the table"
        else:
            name = self._name_of(other)
            what = repr(name) if name is not None else "an object"
        return f"{fn} stopped: {who} touched {what} with the tool at {_fmt(at)}; the arm stays there"

    # ------------------------------------------------------------------ suction
    def suction_on(self) -> bool:
        """Switch the suction on: it grips the movable object the cup touches now, if any (the weld
        engages only on contact); whether it holds something."""
        w = self.world
        obj = w.suction.grip()
        w.step(self.motion.cfg.grip_dwell_steps)
        if obj is not None:
            self._note_grip()
        return w.suction.held is not None

    def suction_off(self) -> None:
        """Switch the suction off: what it held is let go and the scene perceived again (rgbd)."""
        w = self.world
        was = w.suction.release()
        if was is not None:
            self._recent.add((CUP, was))
        w.step(self.motion.cfg.release_dwell_steps)
        scene = self._perceiving()
        if scene is not None and was is not None:
            moved: dict[int, tuple[float, float, float]] = {}
            if self._gripped is not None:
                pid, centre, tip = self._gripped
                moved[pid] = tuple(float(v) for v in centre + (w.tip_pose()[0] - tip))  # type: ignore[assignment]
            scene.refresh(moved)
        self._gripped = None

    def _note_grip(self) -> None:
        """Perceived mode: which perceived object the robot now carries (the movable one nearest
        the tip, within 5 cm), to tell the tracker where it went."""
        if self._perceiving() is None:
            return
        tip = self.world.tip_pose()[0]
        best: tuple[float, int, np.ndarray] | None = None
        for o in self._api.objects():
            if o.fixed:
                continue
            c = self._api.position(o.obj_id)
            dist = math.hypot(c[0] - tip[0], c[1] - tip[1])
            if best is None or dist < best[0]:
                best = (dist, o.obj_id, c)
        self._gripped = (best[1], best[2], tip) if best is not None and best[0] < 0.05 else None

    def _perceiving(self) -> _Perceiving | None:
        scene = getattr(self._api, "scene", None)
        return scene if scene is not None and hasattr(scene, "refresh") else None


def _fmt(v: Any) -> str:
    return str([round(float(x), 3) for x in np.asarray(v, float).ravel()])


def as_points(waypoints: Any, yaw: float, read: Callable[[Any], np.ndarray]) -> list[tuple[np.ndarray, float]]:
    """Waypoints as (position, yaw) pairs: each ``[x, y, z]`` (at the yaw before it, ``yaw`` for
    the first) or ``([x, y, z], yaw)``."""
    out = []
    for w in waypoints:
        if isinstance(w, (list, tuple)) and len(w) == 2 and not isinstance(w[0], (int, float, np.number)):
            pos, yaw = read(w[0]), float(w[1])
        else:
            pos = read(w)
        out.append((pos, yaw))
    return out


__all__ = ["CONTACT_DEPTH", "ContactWatch", "MOVES_PER_PRIMITIVE", "RobotDriver", "TABLE_Z", "as_points"]
