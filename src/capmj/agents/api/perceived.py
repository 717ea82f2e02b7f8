"""The planner API answered from the cameras (``--perception rgbd``) instead of the simulator.

:class:`PerceivedAPI` is the :class:`~capmj.agents.api.planner_api.PlannerAPI` with its view of the table
swapped: names, positions, yaws, boxes and footprints come from :class:`PerceivedScene`, the
tracked detections of the built-in perceiver (:mod:`capmj.perception`), never from the world's
object state.  Everything else is unchanged — name resolution, argument checks, logging, the
footprint geometry — so every prompt, example and reference plan runs as it is.

The world is still used for what a real robot has: rendering its cameras (RGB + depth only,
through :class:`capmj.perception.RGBDBundle`), its clock, and the pick-and-place primitive,
which acts in real physics at the *perceived* position, so a wrong estimate is a real miss.  The
scene is perceived once at the start and again after every pick-and-place.  Pictures are taken
without the arm in them (as after moving it out of view; it is not moved), and each move the robot
made is handed to the tracker, so the moved object keeps its id and blocks hidden in a tower keep
theirs (:class:`capmj.perception.track.Tracker`).

The primitive reports which object it gripped by its simulator id; the robot only knows that it
gripped something, so the result is translated to the perceived object at the pick point.

Beside the API runs a :class:`~capmj.agents.api.perception_audit.PerceptionAudit`: it scores every
view against the truth for the episode's record (never feeding anything back into perception),
and tells the API when a failed pick missed because the perceived point was off the object, so
that the failure is raised as :class:`~capmj.errors.PerceptionFailed` (same text, its own class).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Callable

import numpy as np

from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.base import EpisodeContext
from capmj.agents.api.footprints import Footprints
from capmj.agents.api.perception_audit import PerceptionAudit
from capmj.errors import MotionFailed, PerceptionFailed
from capmj.perception import ClassicalPerceiver, Perceiver, RGBDBundle
from capmj.perception.plugins import STATE, load_perceiver
from capmj.perception.track import Tracker
from capmj.sim.motion import PrimitiveResult
from capmj.sim.objects import ObjectSpec
from capmj.sim.pose import yaw_quat
from capmj.sim.state import Pose

class PerceivedScene:
    """What the robot knows of the table: the tracked detections, as specs, poses and boxes.

    It offers the part of :class:`~capmj.sim.world.World` the planner API reads (``objects``,
    ``objects_by_id``, ``pose``, ``aabb``, ``top_z``, ``time``), answered from perception.
    """

    def __init__(self, world: Any, perceiver: Perceiver | None = None,
                 observer: Callable[[Tracker], None] | None = None) -> None:
        from capmj.sim.cameras import CameraRig

        self._world = world
        self._perceiver: Perceiver = perceiver or ClassicalPerceiver()
        self._observer = observer
        """Called with each new tracker (the audit scoring it for the record)."""
        self._rig = CameraRig(world)
        self.calls = 0
        self.tracker = Tracker.start(self._perceive())
        self._observed()

    def _observed(self) -> None:
        if self._observer is not None:
            self._observer(self.tracker)

    def _perceive(self) -> tuple:
        frames = [self._rig.render(name, seg=False, include_robot=False) for name in self._rig.camera_names]
        self.calls += 1
        return self._perceiver.perceive(RGBDBundle.from_frames(frames))

    def refresh(self, moved: dict[int, tuple[float, float, float]]) -> None:
        """Perceive again after the robot moved the objects in ``moved`` (id -> where it put them)."""
        self.tracker = self.tracker.update(self._perceive(), moved)
        self._observed()

    def restart(self) -> None:
        """Perceive afresh after the world went back to its initial scene (a plan's ``reset()``):
        a new track, as at the start, since no move of the robot explains the change."""
        self.tracker = Tracker.start(self._perceive())
        self._observed()

    def close(self) -> None:
        self._rig.close()

    # ------------------------------------------------------------------ the World subset
    @property
    def time(self) -> float:
        return float(self._world.time)

    @property
    def objects(self) -> tuple[ObjectSpec, ...]:
        out = []
        for t in self.tracker.objects:
            d = t.detection
            out.append(ObjectSpec(t.obj_id, d.kind, d.color, d.position, d.yaw, d.size, d.scale))  # type: ignore[arg-type]
        return tuple(out)

    @property
    def objects_by_id(self) -> dict[int, ObjectSpec]:
        return {o.obj_id: o for o in self.objects}

    def pose(self, obj_id: int) -> Pose:
        d = self.tracker.by_id(obj_id).detection
        return Pose.of(d.position, yaw_quat(d.yaw))

    def aabb(self, obj_id: int) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self.tracker.by_id(obj_id).detection.aabb
        return np.array(lo, float), np.array(hi, float)

    def top_z(self, obj_id: int) -> float:
        return float(self.tracker.by_id(obj_id).detection.aabb[1][2])

    def footprints(self) -> Footprints:
        """The planner's footprints of the perceived specs and poses: the same model as in state
        mode (:mod:`capmj.sim.footprint`), so a fixture's walls are where the file builds them."""
        return Footprints(lambda: self.objects, self.pose, self.top_z)


class PerceivingContext:
    """The episode context as the perceived API uses it: every pick-and-place is followed by a
    fresh perception, and the gripped object is named by perception, not by the simulator."""

    def __init__(self, ctx: EpisodeContext, scene: PerceivedScene, audit: PerceptionAudit) -> None:
        self._ctx = ctx
        self._scene = scene
        self._audit = audit
        self.missed = False
        """Whether the latest pick missed because of perception (:meth:`PerceptionAudit.pick_missed`)."""

    def __getattr__(self, name: str) -> Any:
        return getattr(self._ctx, name)

    def pick_and_place(self, pick: np.ndarray, place: np.ndarray, place_yaw: float | None = None) -> PrimitiveResult:
        held = self._held_at(pick)
        res = self._ctx.pick_and_place(pick, place, place_yaw)
        self.missed = self._audit.pick_missed(held, pick, res.obj_id if res.ok else None)
        gripped = held if res.obj_id is not None else None
        moved = {held: tuple(float(v) for v in place)} if res.ok and held is not None else {}
        self._scene.refresh(moved)  # type: ignore[arg-type]
        return replace(res, obj_id=gripped)

    def _held_at(self, pick: np.ndarray) -> int | None:
        """The perceived movable object whose footprint centre is nearest the pick point (xy)."""
        best: tuple[float, int] | None = None
        for o in self._scene.objects:
            if o.fixed:
                continue
            dist = math.hypot(o.pos[0] - float(pick[0]), o.pos[1] - float(pick[1]))
            if best is None or dist < best[0]:
                best = (dist, o.obj_id)
        return best[1] if best is not None and best[0] < 0.05 else None


class PerceivedAPI(PlannerAPI):
    """The planner API over :class:`PerceivedScene` (see the module docstring)."""

    def __init__(self, ctx: EpisodeContext, perceiver: Perceiver | None = None, name: str = "rgbd") -> None:
        super().__init__(ctx)
        audit = PerceptionAudit(ctx, name)
        self.scene = PerceivedScene(ctx.world, perceiver, observer=audit.observe)
        self._world = self.scene  # type: ignore[assignment]
        self._perceiving = PerceivingContext(ctx, self.scene, audit)
        self._ctx = self._perceiving  # type: ignore[assignment]
        self._footprints = self.scene.footprints()

    def reset_scene(self) -> None:
        super().reset_scene()
        self.scene.restart()

    def put(self, obj: Any, target: Any) -> None:
        """The API's pick-and-place; a miss perception caused is a :class:`PerceptionFailed`."""
        self._perceiving.missed = False
        try:
            super().put(obj, target)
        except MotionFailed as exc:
            if self._perceiving.missed:
                raise PerceptionFailed(str(exc), status=exc.status) from exc
            raise


def make_api(ctx: EpisodeContext, perception: str = "state") -> PlannerAPI:
    """The planner API of an episode in a perception mode: ``state`` or the name of a perceiver
    (built-in or a ``capmj.perceivers`` plugin, :mod:`capmj.perception.plugins`); an unknown name
    is a ConfigError listing the valid ones."""
    if perception == STATE:
        return PlannerAPI(ctx)
    return PerceivedAPI(ctx, load_perceiver(perception), name=perception)


__all__ = ["PerceivedAPI", "PerceivedScene", "PerceivingContext", "make_api"]
