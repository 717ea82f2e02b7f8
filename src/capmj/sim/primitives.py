"""The Ravens pick-and-place primitive with weld suction, as real physics.

Sequence: rise to a transit height that clears every object on the table, move above the pick
point, descend until the cup touches, grip, lift, transit, descend until the carried object
touches something, release, retreat, let the objects come to rest.  Over-and-down and
lift-carry-and-down are each one :meth:`~capmj.sim.motion.Motion.move_through`, their corners rounded
within ``MotionConfig.blend``, so the carried object keeps at least ``clearance - blend`` above every
object.  Where the lift to that one transit height is out of reach at the pick point (a far corner,
a tall tower elsewhere), the carry rises on a slope instead, clearing what it passes over
(:mod:`capmj.sim.carry`).  Nothing is teleported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from capmj.errors import MotionPlanningError
from capmj.sim.carry import sloped_transit
from capmj.sim.motion import Motion, PrimitiveResult, Waypoints
from capmj.sim.motion_config import MotionConfig
from capmj.sim.robot import CUP_RADIUS
from capmj.sim.world import World

_QUARTER = math.pi / 2

AT_HEIGHT_TOL = 1e-3
"""m: a tip this close below the transit height is already there; it does not rise first."""

PLACE_INSIDE_TOL = 0.005
"""m: a place target (given with its height) that puts the carried object deeper than this into
anything is inside it: refused as ``no_path`` before the carry (an exact place on a surface touches
it, within a few millimetres of its height)."""

YAW_QUARTER_TURNS = range(-4, 5)
"""Quarter turns tried around the current yaw when choosing a pick yaw: up to a full turn either
way, so every tool yaw equivalent for the round cup within the wrist's reach is a candidate (the
nearest to the current yaw wins a tie)."""


@dataclass(frozen=True)
class _Failure:
    """Why a step of the primitive ended it: the result's status, the gripped object, the message."""

    status: str
    obj: int | None
    message: str


@dataclass(frozen=True, eq=False)
class _Carry:
    """Where a gripped object is carried: computed once the grip holds (step 2), followed by the
    carry (step 3) and the retreat (step 4)."""

    tip: np.ndarray      # tip position after the grip
    hang: float          # m from the tip down to the carried object's bottom
    transit: float       # tip height at which the carried object clears every object
    yaw: float           # tool yaw at the pick
    new_yaw: float       # tool yaw at the place (the object turned to its place yaw)
    offset: np.ndarray   # the object's centre relative to the tip
    tip_xy: np.ndarray   # tip xy over the place point
    down: np.ndarray     # where the guarded descent over the place point ends


def _wrap(a: float, period: float) -> float:
    """``a`` reduced to [-period/2, period/2)."""
    return (a + period / 2) % period - period / 2


class Primitives:
    """Pick-and-place over one world; keeps the wrist yaw between calls."""

    def __init__(self, world: World, config: MotionConfig | None = None, seed: int = 0) -> None:
        self.world = world
        self.motion = Motion(world, config, seed)
        self.cfg = self.motion.cfg

    # ------------------------------------------------------------------ geometry
    def coarse_top_under(self, xy: np.ndarray, exclude: int | None = None, radius: float = CUP_RADIUS) -> float:
        """Highest coarse-box top (m) of any object under a disc of ``radius`` at ``xy`` (0 for the
        bare table): where a guarded descent there can first meet something.

        A deliberately coarse, conservative bound for motion, not a footprint: the objects' world
        axis-aligned boxes (:meth:`~capmj.sim.world.World.object_boxes`) grown by the cup's
        radius, zones counted, a bowl's rim rather than its floor.  The descent starts
        ``approach_gap`` above it and stops at contact anyway.  It is not the height an object
        comes to rest on (a bowl's floor, never a zone): that is the planner API's
        :meth:`capmj.agents.api.footprints.Footprints.support_z`, on capmj's one footprint model
        (:mod:`capmj.sim.footprint`).
        """
        ids, lo, hi = self.world.object_boxes()
        under = (ids != exclude) & (lo[:, 0] - radius <= xy[0]) & (xy[0] <= hi[:, 0] + radius) \
            & (lo[:, 1] - radius <= xy[1]) & (xy[1] <= hi[:, 1] + radius)
        return float(hi[under, 2].max(initial=0.0))

    def coarse_top(self, exclude: int | None = None) -> float:
        """Highest coarse-box top (m) of any object on the whole table (0 for the bare table):
        transit clears it."""
        ids, _, hi = self.world.object_boxes()
        return float(hi[ids != exclude, 2].max(initial=0.0))

    def transit_height(self, exclude: int | None = None, hang: float = 0.0) -> float:
        """Tip height (m) for moving sideways: ``clearance`` above every object's top (but
        ``exclude``, the carried one) plus ``hang``, how far a carried object reaches below the tip."""
        return max(self.cfg.min_transit_z, self.coarse_top(exclude=exclude) + self.cfg.clearance + hang)

    def _unwound_yaw(self, pos: np.ndarray) -> float:
        """A tool yaw for reaching ``pos`` that keeps the last wrist joint near zero.

        The cup is round, so any yaw picks equally well; but each placement turns the wrist by up
        to 45°, and IK continuity would let those turns add up until wrist 3 hits its ±2π limit.
        Among yaws a quarter turn apart, take the one whose IK has the smallest wrist-3 angle.
        """
        m = self.motion
        base = m.commanded_yaw()
        q_near = self.world.arm_ctrl()
        q = m.ik.solve_analytic(pos, base, q_near)
        if q is None:
            return base
        lo, hi = m.ik.lo[5], m.ik.hi[5]
        best, best_cost = base, (np.inf, 0)
        for k in YAW_QUARTER_TURNS:
            # Turning the tool's yaw by k quarter turns turns wrist 3 the other way and leaves the
            # other joints as they are: one analytic solve serves every candidate.  Wrist 3 is
            # taken, as the solver does, within half a turn of its current angle.
            q5 = (q[5] - k * _QUARTER - q_near[5] + math.pi) % (2 * math.pi) + q_near[5] - math.pi
            cost = (round(abs(q5), 9), abs(k))  # rounded: candidates a full turn apart tie exactly
            if lo <= q5 <= hi and cost < best_cost:
                best, best_cost = base + k * _QUARTER, cost
        return best

    def _put_back(self, pick: np.ndarray, yaw: float) -> None:
        """After a failed carry, lower the held object where it was picked and let go.

        A primitive never ends with something dangling from the cup: the next primitive (or the
        final settle) would otherwise drop it wherever the arm happens to be.
        """
        w, m, cfg = self.world, self.motion, self.cfg
        placed = w.suction.held_touches_other
        tip = w.tip_pose()[0]
        m.move_to(np.array([pick[0], pick[1], tip[2]]), yaw, stop=placed)
        m.move_to(np.array([pick[0], pick[1], 0.0]), yaw, speed=cfg.approach_speed, stop=placed, guarded=True)
        w.suction.release()
        w.step(cfg.release_dwell_steps)
        tip = w.tip_pose()[0]
        m.move_to(np.array([tip[0], tip[1], tip[2] + cfg.retreat]), yaw)
        w.settle(cfg.settle_steps, cfg.settle_tol)

    # ------------------------------------------------------------------ primitive
    def pick_and_place(self, pick: np.ndarray, place: np.ndarray, place_yaw: float | None = None) -> PrimitiveResult:
        """Pick at ``pick`` (xy; z ignored) and put the gripped object's centre at ``place``.

        ``place`` may be xy (the object then rests on whatever surface is there) or xyz (the
        object's centre height; the descent still stops at first contact).  ``place_yaw`` is the
        object's final yaw (blocks are symmetric every 90°), None to keep its orientation.
        """
        w = self.world
        steps0, t0, paths0 = w.steps, w.time, len(self.motion.paths)
        pick = np.asarray(pick, float)
        place = np.asarray(place, float)
        pick_t = (float(pick[0]), float(pick[1]), float(pick[2]) if len(pick) > 2 else 0.0)
        place_t = (float(place[0]), float(place[1]), float(place[2]) if len(place) > 2 else float("nan"))

        def result(status: str, obj: int | None, msg: str = "") -> PrimitiveResult:
            final = tuple(float(v) for v in w.pose(obj).pos) if obj is not None else None
            planned: tuple[Waypoints, ...] = tuple(p.tip for p in self.motion.paths[paths0:] if p.planned)
            return PrimitiveResult(status == "ok", status, obj, pick_t, place_t, final,  # type: ignore[arg-type]
                                   w.steps - steps0, w.time - t0, msg, planned)

        if w.suction.held is not None:
            w.suction.release()
        gripped = self._grip(pick, pick_t)
        if isinstance(gripped, _Failure):
            return result(gripped.status, gripped.obj, gripped.message)
        obj, yaw = gripped
        carried = self._carry(obj, yaw, place, place_yaw, pick, place_t)
        if isinstance(carried, _Failure):
            return result(carried.status, carried.obj, carried.message)
        self._release_and_retreat(*carried)
        return result("ok", obj)

    def _grip(self, pick: np.ndarray, pick_t: tuple[float, float, float]) -> _Failure | tuple[int, float]:
        """Step 1: up to the transit height, over and down onto the pick point until the cup
        touches, grip; (the gripped object, the tool yaw), or why not."""
        w, m, cfg = self.world, self.motion, self.cfg
        transit = self.transit_height()
        tip = w.tip_pose()[0]
        try:
            if tip[2] < transit - AT_HEIGHT_TOL:
                if m.move_to(np.array([tip[0], tip[1], transit]), m.commanded_yaw())[0] == "unreachable":
                    return _Failure("unreachable", None, "cannot rise to transit height")
            m.unwind_wrist()
            yaw = self._unwound_yaw(np.array([pick[0], pick[1], transit]))
            over_pick = np.array([pick[0], pick[1], transit])
            surface = self.coarse_top_under(pick[:2])
            touching = lambda: w.suction.touching() is not None  # noqa: E731
            status, _, leg = self._through([(over_pick, yaw), (np.array([pick[0], pick[1], surface - cfg.overshoot]), yaw)],
                                           touching, cfg.approach_gap + cfg.overshoot)
            if status == "unreachable" and (leg == 0 or m.move_to(over_pick, yaw)[0] == "unreachable"):
                return _Failure("unreachable", None, f"pick point {pick_t[:2]} is out of reach")
        except MotionPlanningError as exc:
            return _Failure("no_path", None, f"pick at {pick_t[:2]}: {exc}")
        obj = w.suction.grip()
        if obj is None:
            m.move_to(over_pick, yaw)
            return _Failure("no_grip", None, "descended to the pick point without touching a movable object")
        w.step(cfg.grip_dwell_steps)
        return obj, yaw

    def _plan_carry(self, obj: int, yaw: float, place: np.ndarray, place_yaw: float | None) -> _Carry:
        """Step 2: how high the gripped object must be lifted to clear everything, and where the
        tip goes so that the object's centre ends at ``place``, turned to ``place_yaw``."""
        w, cfg = self.world, self.cfg
        obj_pose = w.pose(obj)
        tip = w.tip_pose()[0]
        hang = tip[2] - (obj_pose.pos[2] - w.objects_by_id[obj].half_extents[2])
        transit = self.transit_height(exclude=obj, hang=hang)
        delta = 0.0 if place_yaw is None else _wrap(place_yaw - obj_pose.yaw, _QUARTER)
        offset = np.asarray(obj_pose.pos) - tip  # object centre relative to the tip
        c, s = math.cos(delta), math.sin(delta)
        offset_xy = np.array([c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]])
        tip_xy = place[:2] - offset_xy
        if len(place) > 2:
            centre_z = float(place[2])
        else:
            centre_z = self.coarse_top_under(place[:2], exclude=obj) + w.objects_by_id[obj].half_extents[2]
        tip_z = centre_z - offset[2]
        down = np.array([tip_xy[0], tip_xy[1], tip_z - cfg.overshoot])
        return _Carry(tip=tip, hang=hang, transit=transit, yaw=yaw, new_yaw=yaw + delta, offset=offset,
                      tip_xy=tip_xy, down=down)

    def _carry(self, obj: int, yaw: float, place: np.ndarray, place_yaw: float | None, pick: np.ndarray,
               place_t: tuple[float, float, float]) -> _Failure | tuple[float, float]:
        """Step 3: lift, carry and go down until the carried object touches (one move, corners
        rounded; on a slope where the lift straight up is out of reach); the tip height over the
        place point, where the retreat rises back to, or why not (the object then put back)."""
        carry = self._plan_carry(obj, yaw, place, place_yaw)
        try:
            place_z = self._carry_moves(obj, carry, pick, place_t)
        except MotionPlanningError as exc:
            self._let_go_here(yaw)
            return _Failure("no_path", obj, f"place at {place_t[:2]}: {exc}; object put back")
        return place_z if isinstance(place_z, _Failure) else (place_z, carry.new_yaw)

    def _let_go_here(self, yaw: float) -> None:
        """After a carry found no path (nothing moved since the grip): let go where the object was
        picked, rise and let the objects come to rest."""
        w, m, cfg = self.world, self.motion, self.cfg
        w.suction.release()
        w.step(cfg.release_dwell_steps)
        tip = w.tip_pose()[0]
        try:
            m.move_to(np.array([tip[0], tip[1], tip[2] + cfg.retreat]), yaw)
        except MotionPlanningError:
            pass  # the arm stays where it let go
        w.settle(cfg.settle_steps, cfg.settle_tol)

    def _check_place(self, obj: int, carry: _Carry, place_t: tuple[float, float, float]) -> None:
        """Refuse a place target given with its height that puts the carried object inside
        something (deeper than :data:`PLACE_INSIDE_TOL`): raises MotionPlanningError."""
        m = self.motion
        if not self.cfg.plan_collisions or math.isnan(place_t[2]):
            return
        target = carry.down + np.array([0.0, 0.0, self.cfg.overshoot])
        res = m.ik.solve(target, carry.new_yaw, self.world.arm_ctrl())
        if res.q is None:
            return  # out of reach: the carry reports it
        m.checker.sync()
        inside = m.checker.tool_inside(res.q, PLACE_INSIDE_TOL)
        if inside is not None:
            raise MotionPlanningError(f"the place target {tuple(round(v, 3) for v in place_t)} is inside something: "
                                      f"{inside}", status="no_path")

    def _carry_moves(self, obj: int, carry: _Carry, pick: np.ndarray, place_t: tuple[float, float, float]
                     ) -> _Failure | float:
        """The moves of :meth:`_carry` (which catches a MotionPlanningError they raise)."""
        w, m, cfg = self.world, self.motion, self.cfg
        tip, transit, yaw, new_yaw, tip_xy, down = carry.tip, carry.transit, carry.yaw, carry.new_yaw, carry.tip_xy, carry.down
        self._check_place(obj, carry, place_t)
        placed = w.suction.held_touches_other
        place_z = transit  # the tip height over the place point, where the retreat rises back to
        legs = [(np.array([tip[0], tip[1], transit]), yaw), (np.array([tip_xy[0], tip_xy[1], transit]), new_yaw),
                (down, new_yaw)]
        lifts = 1  # legs[:lifts] lift the object; then the carry over the place point, then the descent
        status, _, leg = self._through(legs, placed, cfg.approach_gap + cfg.overshoot)
        if status == "unreachable" and leg == 0:
            # Out of reach straight up: only what the carry passes over needs clearing (the carried
            # object's footprint around the tip), on a slope between the highest reachable heights.
            lo, hi = w.aabb(obj)
            radius = float(np.linalg.norm(carry.offset[:2])) + float(np.linalg.norm(hi[:2] - lo[:2])) / 2
            sloped = sloped_transit(w, m.ik, tip[:2], tip_xy, yaw, radius, transit, cfg.min_transit_z,
                                    cfg.clearance + carry.hang, obj)
            if sloped is not None:
                *via, above = sloped  # up at the pick point, then rising along the way; above the place point
                place_z = float(above[2])
                legs = [(point, yaw) for point in via] + [(np.array([tip_xy[0], tip_xy[1], place_z]), new_yaw),
                                                          (down, new_yaw)]
                lifts = len(via)
                status, _, leg = m.move_through(legs, stop=placed, slow_last=cfg.approach_gap + cfg.overshoot,
                                                contact_before=cfg.overshoot, guarded=True)
        if status == "unreachable" and leg == len(legs) - 1:  # no descent: carry over the place point, let go there
            status, _, leg = m.move_through(legs[:-1])
        if status == "unreachable":
            self._put_back(pick, yaw)
            if leg < lifts:
                return _Failure("unreachable", obj, "cannot lift to transit height")
            return _Failure("unreachable", obj, f"place point {place_t[:2]} is out of reach; object put back")
        return place_z

    def _through(self, legs: list[tuple[np.ndarray, float]], stop: Callable[[], bool],
                 slow_last: float) -> tuple[str, int, int]:
        """:meth:`Motion.move_through` of ``legs`` ending in a guarded descent (the last leg, from
        the point of the one before).  When that has no clear path, the arm tries the descent in
        another posture: the legs before as they were, then a joint-space move to another IK
        branch over the descent (a wrist or elbow turned the other way puts the links that
        touched elsewhere; :meth:`Motion.branches`), then the descent; the first posture whose
        legs are all clear is taken.  The same when the transit into the descent or the descent
        is unreachable in the current posture (the IK branch the lines follow).  Raises the first
        MotionPlanningError, or returns the first outcome, when no posture helps."""
        m = self.motion
        first: MotionPlanningError | tuple[str, int, int]
        depth = self.cfg.overshoot  # the descent's expected contact lies this far before its end
        try:
            first = m.move_through(legs, stop=stop, slow_last=slow_last, contact_before=depth, guarded=True)
            if first[0] != "unreachable" or first[2] < len(legs) - 2:
                return first
        except MotionPlanningError as exc:
            first = exc
        if not self.cfg.plan_collisions or len(legs) < 2:
            return self._give_up(first)
        (over, yaw), (down, down_yaw) = legs[-2], legs[-1]
        before = m.plan_lines(legs[:-2]) if len(legs) > 2 else []
        if isinstance(before, int):
            return self._give_up(first)
        q_here = before[-1].qs[-1] if before else self.world.arm_ctrl()
        for q_alt in m.branches(over, yaw):
            descent = m.plan_lines([(down, down_yaw)], slow_last=slow_last, q_start=q_alt)
            if isinstance(descent, int):
                continue
            try:
                checked = m.clear_legs([*before, m.joint_plan(np.array([q_here, q_alt])), *descent], guarded=True,
                                       contact_before=depth)
            except MotionPlanningError:
                continue
            status, steps = m.run_legs(checked, np.asarray(down, float), stop)
            return status, steps, -1
        return self._give_up(first)

    @staticmethod
    def _give_up(first: MotionPlanningError | tuple[str, int, int]) -> tuple[str, int, int]:
        """The first outcome of :meth:`_through` when no other posture helped: raised again if it
        was a MotionPlanningError, else returned."""
        if isinstance(first, MotionPlanningError):
            raise first
        return first

    def _release_and_retreat(self, place_z: float, yaw: float) -> None:
        """Step 4: let go, rise and let the objects come to rest."""
        w, m, cfg = self.world, self.motion, self.cfg
        w.suction.release()
        w.step(cfg.release_dwell_steps)
        # Retreat straight up, on to the height the next primitive starts its transit at: one
        # vertical move instead of a retreat that stops and a rise that starts again.
        tip = w.tip_pose()[0]
        up = min(place_z, tip[2] + cfg.retreat)
        try:
            if m.move_to(np.array([tip[0], tip[1], max(up, self.transit_height())]), yaw)[0] == "unreachable":
                m.move_to(np.array([tip[0], tip[1], up]), yaw)
        except MotionPlanningError:
            pass  # the arm stays over the placed object; the next move starts from there
        w.settle(cfg.settle_steps, cfg.settle_tol)
