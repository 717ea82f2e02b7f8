"""The planner API: the only thing LLM-written plan code can touch.

:class:`PlannerAPI` wraps one :class:`~capmj.agents.base.EpisodeContext` and hands out plain
functions through :meth:`PlannerAPI.functions`: the methods of
:class:`~capmj.agents.api.plan_functions.PlanFunctions` (one per API function, named in
:data:`~capmj.agents.api.plan_functions.API_FUNCTIONS`), each wrapped in a closure that logs the call.
Sandboxed code cannot reach a closure's cells (dunder and ``_private`` attribute access is rejected by the sandbox), and every
value the functions return is plain data (str, float, list, tuple, dict, numpy array), so there is
no public attribute path from plan code to the ``World``, ``MjModel`` or ``MjData``.

Conventions (the spec's, stated at every function):

* Positions are metres in the world frame: robot base at the origin, table top at z = 0,
  workspace x ∈ [0.25, 0.75], y ∈ [−0.5, 0.5].  left = y−, right = y+, front = x+, rear = x−;
  "top/bottom" of the workspace, an area or a corner = x−/x+ (front-camera image).
* Rotations at this API are quaternions **(x, y, z, w)** (MuJoCo and ``Pose`` use (w, x, y, z)).
* Object names are the unique ``ObjectSpec.name`` strings ("movable small blue block with
  obj_id 3"), read from the live world on every call.  An int obj_id is accepted wherever a name
  is.  A near-miss name resolves when exactly one object fits it (see :func:`~capmj.agents.api.names.near_miss`: missing
  movable/fixed/size words, underscores, an id whose object has the given words, a unique
  colour + kind); each such resolution is logged.  Otherwise ``ValueError`` lists the closest
  and the valid names.
* Footprints: capmj's one footprint model (:mod:`capmj.sim.footprint`, the judge's too): blocks,
  zones and fixture walls are oriented rectangles at the current yaw, bowls and balls discs; an
  object tilted more than 15° uses its world xy box.  The geometry (footprints, surfaces,
  occupancy, free positions) lives in :mod:`capmj.agents.api.footprints`, the reading of names in
  :mod:`capmj.agents.api.names`; this module resolves names, validates arguments and logs.

Every call is appended to :attr:`PlannerAPI.call_log` (function, arguments, result summary or
error, simulated time) for the episode log.
"""

from __future__ import annotations

from typing import Any, Callable, Iterator

import numpy as np

from capmj.agents.api.footprints import Footprints
from capmj.agents.api.names import lookup
from capmj.agents.api.low_level import LEVELS, LOW_LEVEL_FUNCTIONS, LowLevelFunctions
from capmj.agents.api.plan_functions import API_FUNCTIONS, PlanFunctions
from capmj.agents.api.values import ONE_ELEMENT_LISTS, Coordinate
from capmj.agents.api.values import is_pose as _is_pose
from capmj.agents.api.values import is_vector as _is_vector
from capmj.agents.api.values import summary as _summary
from capmj.agents.base import EpisodeContext
from capmj.errors import ConfigError, MotionFailed, PortingDifference, describe
from capmj.sim.bounds import WORKSPACE
from capmj.sim.objects import ObjectSpec
from capmj.sim.pose import quat_yaw, wxyz
from capmj.sim.world import World
from capmj.tasks.protocol import episode_rng


class PlannerAPI:
    """The planner-facing facade of one episode (see the module docstring for conventions)."""

    def __init__(self, ctx: EpisodeContext) -> None:
        self._ctx = ctx
        self._world = ctx.world
        self._rng = episode_rng(ctx.seed, "api")
        self.call_log: list[dict[str, Any]] = []
        """One entry per API call: ``{"i", "fn", "args", "result" | "error", "sim_time"}``."""
        self.messages: list[str] = []
        """What the plan said through ``say``."""
        self.said_chars = 0
        """Characters of :attr:`messages` together (capped by the context's ``Budget.max_said_chars``)."""
        self._footprints = Footprints.from_world(self._world)
        """Table geometry (footprints, surfaces, occupancy, free positions), read live."""
        self.resolved: list[tuple[str, str]] = []
        """(name as written, object it was resolved to) for every near-miss name accepted."""

    # ================================================================== the facade's interface
    # (what the API functions read and do: capmj.agents.api.interface.PlannerInterface)
    @property
    def ctx(self) -> EpisodeContext:
        """The episode context the API acts through (budgets, recorder, pick-and-place)."""
        return self._ctx

    @property
    def world(self) -> World:
        """The world the API reads (live)."""
        return self._world

    @property
    def footprints(self) -> Footprints:
        """Table geometry (footprints, surfaces, occupancy, free positions), read live."""
        return self._footprints

    def objects(self) -> tuple[ObjectSpec, ...]:
        """Every object's spec, read live on every call."""
        return tuple(self._world.objects)

    def resolve(self, obj: Any) -> ObjectSpec:
        """The spec of a name (exact; case and spacing forgiven; a near miss, logged) or an int
        obj_id (:func:`capmj.agents.api.names.lookup`)."""
        fit, near = lookup(obj, self.objects())
        if near:
            self.resolved.append((obj, fit.name))
            if self.call_log:  # the call being made: the log shows what the name meant
                self.call_log[-1].setdefault("resolved", []).append(f"{obj!r} -> {fit.name!r}")
        return fit

    # ================================================================== poses
    def position(self, oid: int) -> np.ndarray:
        return np.asarray(self._world.pose(oid).pos, float)

    def quat_xyzw(self, oid: int) -> list[float]:
        return [float(v) for v in self._world.pose(oid).quat_xyzw]

    # ================================================================== logging
    def _logged(self, name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def call(*args: Any, **kwargs: Any) -> Any:
            entry: dict[str, Any] = {
                "i": len(self.call_log), "fn": name,
                "args": [_summary(a, 120) for a in args] + [f"{k}={_summary(v, 120)}" for k, v in kwargs.items()],
                "sim_time": round(self._world.time, 4),
            }
            self.call_log.append(entry)
            try:
                result = fn(*args, **kwargs)
            except Exception as exc:
                entry["error"] = describe(exc)
                raise
            entry["result"] = _summary(result)
            return result

        call.__name__ = call.__qualname__ = name
        call.__doc__ = fn.__doc__
        call.__wrapped__ = fn  # type: ignore[attr-defined]  # its signature, for error messages
        return call

    def log_text(self) -> str:
        """The call log as text, one line per call."""
        lines = []
        for e in self.call_log:
            out = f"-> {e['result']}" if "result" in e else f"!! {e.get('error', '(running)')}"
            if e.get("resolved"):
                out += f"  (resolved {', '.join(e['resolved'])})"
            lines.append(f"[{e['i']:3d} t={e['sim_time']:.2f}s] {e['fn']}({', '.join(e['args'])}) {out}")
        return "\n".join(lines)

    def object_names(self) -> list[str]:
        """The names of every object, as this API knows them (unlogged: for prompts and plan globals)."""
        return [o.name for o in self.objects()]

    def objects_text(self) -> str:
        """The ``objects = [...]`` line listing every object of the scene for prompts."""
        return f"objects = {self.object_names()!r}"

    # ================================================================== the API
    def functions(self, level: str = "high") -> dict[str, Callable[..., Any]]:
        """Plain functions for plan code, by name (each call logged in :attr:`call_log`): the
        methods of a :class:`PlanFunctions` over this API named in :data:`API_FUNCTIONS`, or at
        ``level="low"`` those of a :class:`~capmj.agents.api.low_level.LowLevelFunctions` named in
        :data:`~capmj.agents.api.low_level.LOW_LEVEL_FUNCTIONS` (``--api low``)."""
        if level == "low":
            low = LowLevelFunctions(self)
            return {name: self._logged(name, getattr(low, name)) for name in LOW_LEVEL_FUNCTIONS}
        if level != "high":
            raise ConfigError(f"unknown API level {level!r}; valid levels: {', '.join(LEVELS)}")
        fns = PlanFunctions(self)
        logged = {name: self._logged(name, getattr(fns, name)) for name in API_FUNCTIONS}
        fns.use_logged(logged)
        return dict(logged)

    # ================================================================== implementations
    def xy(self, pos: Any) -> np.ndarray:
        """xy of a position, a pose or an object name."""
        if isinstance(pos, (str, int, np.integer)) and not isinstance(pos, bool):
            return self.position(self.resolve(pos).obj_id)[:2]
        if _is_pose(pos):
            pos = pos[0]
        if not _is_vector(pos):
            if isinstance(pos, Coordinate):
                raise PortingDifference(f"expected a position, got one number {pos!r}: {ONE_ELEMENT_LISTS}")
            raise ValueError(f"expected a position [x, y] or [x, y, z], got {_summary(pos, 80)}")
        return np.asarray(pos, float)[:2]

    def occupied(self, targ: Any, r: float) -> list[str]:
        if isinstance(targ, (str, int, np.integer)) and not isinstance(targ, bool):
            return [o.name for o in self._footprints.overlapping(self.resolve(targ))]
        if isinstance(targ, (list, tuple)) and len(targ) == 1 and (_is_vector(targ[0]) or _is_pose(targ[0])):
            targ = targ[0]  # the original API's one-element position lists
        if (isinstance(targ, (list, tuple)) and len(targ) > 1 and not _is_vector(targ) and not _is_pose(targ)
                and all(_is_vector(t) or _is_pose(t) for t in targ)):
            hits = [o.name for t in targ for o in self._footprints.within(self.xy(t), r)]
            return list(dict.fromkeys(hits))  # several target positions: what occupies any of them
        return [o.name for o in self._footprints.within(self.xy(targ), r)]

    def free_position(self, targ: Any, area: Any, r: float) -> list[float]:
        if area is None and targ is not None and _is_vector(targ, (4,)):
            area, targ = targ, None  # the original accepted the search area as the first argument
        if area is None:
            area = WORKSPACE.xyxy
        if not _is_vector(area, (4,)):
            raise ValueError(f"area must be (xmin, ymin, xmax, ymax) in metres, got {_summary(area, 80)}")
        if not r >= 0:
            raise ValueError(f"r must be a clearance >= 0 in metres, got {r}")

        def reserved() -> Iterator[np.ndarray]:
            # lazy, so that a bad area is reported before a bad targ (as the search checks it first)
            for t in self._targets(targ):
                yield self.xy(t)

        return self._footprints.free_position(area, r, self._rng, reserved())

    def _targets(self, targ: Any) -> list[Any]:
        """``targ`` of get_random_free_pos as a list of names / positions / poses."""
        if targ is None:
            return []
        if isinstance(targ, (str, int, np.integer)) or _is_vector(targ) or _is_pose(targ):
            return [targ]
        if isinstance(targ, (list, tuple, np.ndarray)):
            return list(targ)
        raise ValueError(f"targ must be a name, a position, a pose or a list of them, got {_summary(targ, 80)}")

    def reset_scene(self) -> None:
        """The episode's initial scene back, within the attempt (a plan's ``reset()``)."""
        self._ctx.reset_scene()

    def put(self, obj: Any, target: Any) -> None:
        w = self._world
        if obj is None or target is None:
            raise ValueError("put_first_on_second needs an object and a target")
        # --- what to pick
        held: ObjectSpec | None = None
        if _is_vector(obj) or _is_pose(obj):
            pick = self.xy(obj)
        else:
            held = self.resolve(obj)
            if held.fixed:
                raise PortingDifference(f"{held.name!r} is fixed and cannot be picked")
            above = self._footprints.resting_on(held)
            if above:
                raise ValueError(f"cannot pick {held.name!r}: {above[0].name!r} lies on top of it; move that first")
            pick = self.position(held.obj_id)[:2]
        exclude = {held.obj_id} if held is not None else set()
        half = held.half_extents[2] if held is not None else 0.02
        # --- where to put it
        yaw: float | None = None
        if isinstance(target, (str, int, np.integer)) and not isinstance(target, bool):
            t = self.resolve(target)
            if held is not None and t.obj_id == held.obj_id:
                raise ValueError(f"cannot put {held.name!r} on itself")
            c = self.position(t.obj_id)
            xy = c[:2]
            if t.kind == "bowl":
                surface = self._footprints.support_z(xy, exclude)
            else:
                surface = max(self._footprints.support_z(xy, exclude), 0.0 if t.kind == "zone" else w.top_z(t.obj_id))
                if t.kind in ("block", "zone"):
                    yaw = w.pose(t.obj_id).yaw  # line the object up with what it goes on
            place = np.array([xy[0], xy[1], surface + half])
        else:
            if isinstance(target, (list, tuple)) and len(target) == 1:
                target = target[0]  # the original API's one-element position lists
            # A bare position is the pose (position, identity), as in CapRavens: the object ends
            # aligned with the world axes, so grids of bare positions do not overlap.
            yaw = 0.0
            if _is_pose(target):
                yaw = quat_yaw(wxyz(target[1]))
                target = target[0]
            if not _is_vector(target):
                if isinstance(target, Coordinate):
                    raise PortingDifference(f"target is one number, {target!r}: {ONE_ELEMENT_LISTS}")
                raise ValueError("target must be an object name, [x, y], [x, y, z] or (position, quaternion "
                                 f"xyzw), got {_summary(target, 80)}")
            p = np.asarray(target, float)
            rest = self._footprints.support_z(p[:2], exclude) + half
            place = np.array([p[0], p[1], max(rest, float(p[2])) if len(p) == 3 else rest])
        if not np.all(np.isfinite(place)):
            raise ValueError(f"target position {place.tolist()} is not finite")
        res = self._ctx.pick_and_place(np.array([pick[0], pick[1], 0.0]), place, yaw)
        what = held.name if held is not None else f"the object at {np.round(pick, 3).tolist()}"
        if not res.ok:
            raise MotionFailed(f"put_first_on_second({what!r}) failed: {res.status}: {res.message}", status=res.status)
        if held is not None and res.obj_id != held.obj_id:
            got = w.objects_by_id[res.obj_id].name if res.obj_id in w.objects_by_id else res.obj_id
            raise MotionFailed(f"put_first_on_second: picked {got!r} instead of {held.name!r}", status="wrong_object")


__all__ = ["PlannerAPI"]
