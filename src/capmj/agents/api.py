"""The planner API: the only thing LLM-written plan code can touch.

:class:`PlannerAPI` wraps one :class:`~capmj.agents.base.EpisodeContext` and hands out plain
functions through :meth:`PlannerAPI.functions`: the methods of :class:`PlanFunctions` (one per API
function, named in :data:`API_FUNCTIONS`), each wrapped in a closure that logs the call.
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
  is.  A near-miss name resolves when exactly one object fits it (see :func:`near_miss`: missing
  movable/fixed/size words, underscores, an id whose object has the given words, a unique
  colour + kind); each such resolution is logged.  Otherwise ``ValueError`` lists the closest
  and the valid names.
* Footprints: capmj's one footprint model (:mod:`capmj.sim.footprint`, the judge's too): blocks,
  zones and fixture walls are oriented rectangles at the current yaw, bowls and balls discs; an
  object tilted more than 15° uses its world xy box.  The geometry (footprints, surfaces,
  occupancy, free positions) lives in :mod:`capmj.agents.footprints`; this module resolves names,
  validates arguments and logs.

Every call is appended to :attr:`PlannerAPI.call_log` (function, arguments, result summary or
error, simulated time) for the episode log.
"""

from __future__ import annotations

import difflib
import re
from typing import Any, Callable, Iterator, Mapping, Sequence

import numpy as np

from capmj.agents.api_values import ONE_ELEMENT_LISTS, Coordinate, denormalize_uv
from capmj.agents.api_values import is_pose as _is_pose
from capmj.agents.api_values import is_vector as _is_vector
from capmj.agents.api_values import summary as _summary
from capmj.agents.base import EpisodeContext
from capmj.agents.capravens_api import CapRavensFunctions
from capmj.agents.footprints import FREE_CLEARANCE, FREE_GRID_STEP, REACH_RADIUS, Footprints
from capmj.errors import MotionFailed, PortingDifference, UnknownObjectError, describe
from capmj.sim.bounds import WORKSPACE
from capmj.sim.footprint import ROUND_KINDS
from capmj.sim.objects import ObjectSpec
from capmj.sim.pose import quat_euler_xyz, quat_yaw, wxyz
from capmj.tasks.protocol import episode_rng

CORNER_NAMES = ("top left corner", "top right corner", "bottom left corner", "bottom right corner")
SIDE_NAMES = ("top side", "right side", "bottom side", "left side")
_CORNERS_UV = ((0.0, 1.0), (1.0, 1.0), (0.0, 0.0), (1.0, 0.0))
_SIDES_UV = ((0.5, 1.0), (1.0, 0.5), (0.5, 0.0), (0.0, 0.5))


_FILLER = frozenset({"the", "a", "an", "with", "obj", "id", "object", "of"})


def _words(text: str) -> list[str]:
    return re.findall(r"[a-z]+|\d+", text.lower().replace("_", " "))


def near_miss(query: str, objects: Sequence[ObjectSpec]) -> ObjectSpec | None:
    """The one object a near-miss name can only mean, else None.

    The query's words (case, ``_`` and punctuation ignored; "the", "with", "obj_id" ... dropped)
    must all be words of the object's name, and a number in the query must be its obj_id:
    ``'brown bowl'`` (one brown bowl), ``'movable_blue_block_with_obj_id_3'``, ``'yellow block
    with obj_id 4'``.  Two or more fitting objects, or none, give None: nothing is guessed.
    """
    words = _words(query)
    ids = {int(w) for w in words if w.isdigit()}
    words = [w for w in words if not w.isdigit() and w not in _FILLER]
    if len(ids) > 1 or not (words or ids):
        return None
    fits = [o for o in objects if (not ids or o.obj_id in ids) and set(words) <= set(_words(o.name))]
    return fits[0] if len(fits) == 1 else None


def porting_difference(obj: str, objs: Sequence[ObjectSpec]) -> None:
    """PortingDifference for an unknown name that CapRavens' scenes could have had: a fixed
    block (capmj's blocks are all movable) or obj_id 0 (capmj's ids count from 1)."""
    words = _words(obj)
    if "fixed" in words:
        fit = near_miss(" ".join(w for w in words if w != "fixed"), objs)
        if fit is not None and not fit.fixed:
            raise PortingDifference(f"unknown object {obj!r}: capmj has no fixed {fit.kind}s (every {fit.kind} "
                                    f"is movable, unlike CapRavens' fixed blocks); the {fit.kind} meant is "
                                    f"{fit.name!r}")
    if re.search(r"obj_id\s*0\b", obj):
        raise PortingDifference(f"unknown object {obj!r}: capmj's obj_ids count from 1 (CapRavens' were "
                                f"PyBullet body ids); valid ids: {sorted(o.obj_id for o in objs)}")


def _closest(query: str, names: Sequence[str], n: int = 3) -> list[str]:
    """Names sharing the most words with ``query`` (ties by string similarity)."""
    words = set(_words(query)) - _FILLER

    def score(name: str) -> tuple[int, float]:
        return (len(words & set(_words(name))), difflib.SequenceMatcher(None, query.lower(), name.lower()).ratio())

    return sorted(names, key=score, reverse=True)[:n]


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
        self._footprints = Footprints.from_world(self._world)
        """Table geometry (footprints, surfaces, occupancy, free positions), read live."""
        self.resolved: list[tuple[str, str]] = []
        """(name as written, object it was resolved to) for every near-miss name accepted."""

    # ================================================================== names
    def _objects(self) -> tuple[ObjectSpec, ...]:
        return tuple(self._world.objects)  # read live on every call

    def _names(self) -> list[str]:
        return [o.name for o in self._objects()]

    def _resolve(self, obj: Any) -> ObjectSpec:
        """The spec of a name (exact; case and spacing forgiven) or an int obj_id."""
        objs = self._objects()
        if isinstance(obj, (int, np.integer)) and not isinstance(obj, bool):
            for o in objs:
                if o.obj_id == int(obj):
                    return o
            raise UnknownObjectError(f"no object with obj_id {int(obj)}; valid ids: {sorted(o.obj_id for o in objs)}",
                                     name=int(obj))
        if not isinstance(obj, str):
            raise ValueError(f"expected an object name (str), got {type(obj).__name__} {_summary(obj, 80)}")
        for o in objs:
            if o.name == obj:
                return o
        key = " ".join(obj.lower().split())
        for o in objs:
            if o.name.lower() == key:
                return o
        fit = near_miss(obj, objs)
        if fit is not None:
            self.resolved.append((obj, fit.name))
            if self.call_log:  # the call being made: the log shows what the name meant
                self.call_log[-1].setdefault("resolved", []).append(f"{obj!r} -> {fit.name!r}")
            return fit
        porting_difference(obj, objs)
        names = [o.name for o in objs]
        close = _closest(obj, names)
        hint = f"; closest names: {', '.join(map(repr, close))}" if close else ""
        shown = names[:6]
        more = f" … ({len(names)} objects)" if len(names) > len(shown) else ""
        raise UnknownObjectError(f"unknown object {obj!r}{hint}. Valid names: {', '.join(map(repr, shown))}{more}",
                                 name=obj)

    # ================================================================== poses
    def _pos(self, oid: int) -> np.ndarray:
        return np.asarray(self._world.pose(oid).pos, float)

    def _quat_xyzw(self, oid: int) -> list[float]:
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
        return self._names()

    def objects_text(self) -> str:
        """The ``objects = [...]`` line listing every object of the scene for prompts."""
        return f"objects = {self._names()!r}"

    # ================================================================== the API
    def functions(self) -> dict[str, Callable[..., Any]]:
        """Plain functions for plan code, by name (each call logged in :attr:`call_log`): the
        methods of a :class:`PlanFunctions` over this API named in :data:`API_FUNCTIONS`."""
        fns = PlanFunctions(self)
        logged = {name: self._logged(name, getattr(fns, name)) for name in API_FUNCTIONS}
        fns.use_logged(logged)
        return dict(logged)

    # ================================================================== implementations
    def _xy(self, pos: Any) -> np.ndarray:
        """xy of a position, a pose or an object name."""
        if isinstance(pos, (str, int, np.integer)) and not isinstance(pos, bool):
            return self._pos(self._resolve(pos).obj_id)[:2]
        if _is_pose(pos):
            pos = pos[0]
        if not _is_vector(pos):
            if isinstance(pos, Coordinate):
                raise PortingDifference(f"expected a position, got one number {pos!r}: {ONE_ELEMENT_LISTS}")
            raise ValueError(f"expected a position [x, y] or [x, y, z], got {_summary(pos, 80)}")
        return np.asarray(pos, float)[:2]

    def _occupied(self, targ: Any, r: float) -> list[str]:
        if isinstance(targ, (str, int, np.integer)) and not isinstance(targ, bool):
            return [o.name for o in self._footprints.overlapping(self._resolve(targ))]
        if isinstance(targ, (list, tuple)) and len(targ) == 1 and (_is_vector(targ[0]) or _is_pose(targ[0])):
            targ = targ[0]  # the original API's one-element position lists
        if (isinstance(targ, (list, tuple)) and len(targ) > 1 and not _is_vector(targ) and not _is_pose(targ)
                and all(_is_vector(t) or _is_pose(t) for t in targ)):
            hits = [o.name for t in targ for o in self._footprints.within(self._xy(t), r)]
            return list(dict.fromkeys(hits))  # several target positions: what occupies any of them
        return [o.name for o in self._footprints.within(self._xy(targ), r)]

    def _free_pos(self, targ: Any, area: Any, r: float) -> list[float]:
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
                yield self._xy(t)

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

    def _reset_scene(self) -> None:
        """The episode's initial scene back, within the attempt (a plan's ``reset()``)."""
        self._ctx.reset_scene()

    def _put(self, obj: Any, target: Any) -> None:
        w = self._world
        if obj is None or target is None:
            raise ValueError("put_first_on_second needs an object and a target")
        # --- what to pick
        held: ObjectSpec | None = None
        if _is_vector(obj) or _is_pose(obj):
            pick = self._xy(obj)
        else:
            held = self._resolve(obj)
            if held.fixed:
                raise PortingDifference(f"{held.name!r} is fixed and cannot be picked")
            above = self._footprints.resting_on(held)
            if above:
                raise ValueError(f"cannot pick {held.name!r}: {above[0].name!r} lies on top of it; move that first")
            pick = self._pos(held.obj_id)[:2]
        exclude = {held.obj_id} if held is not None else set()
        half = held.half_extents[2] if held is not None else 0.02
        # --- where to put it
        yaw: float | None = None
        if isinstance(target, (str, int, np.integer)) and not isinstance(target, bool):
            t = self._resolve(target)
            if held is not None and t.obj_id == held.obj_id:
                raise ValueError(f"cannot put {held.name!r} on itself")
            c = self._pos(t.obj_id)
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


class PlanFunctions(CapRavensFunctions):
    """The planner API functions of one episode, one method each, over a :class:`PlannerAPI`.

    The methods named in :data:`API_FUNCTIONS` are what plan code calls: their names, signatures
    and docstrings are the API the prompts document.  :meth:`PlannerAPI.functions` hands them out
    wrapped for the call log; a method calling another calls it unlogged (``get_obj_pos`` of a list
    is one logged call), except that :meth:`stack_objects_in_order` logs each step it takes
    (through the logged functions given to :meth:`use_logged`).  Names are resolved, arguments
    checked and logged by the :class:`PlannerAPI`, and the geometry is :mod:`capmj.agents.footprints`.
    """

    def __init__(self, api: PlannerAPI) -> None:
        self._api = api
        self._logged: Mapping[str, Callable[..., Any]] = {}

    def use_logged(self, logged: Mapping[str, Callable[..., Any]]) -> None:
        """The logged versions of these functions, for the ones that call others as steps."""
        self._logged = logged

    def get_obj_names(self) -> list[str]:
        """Names of every object in the scene (read from the live world)."""
        return self._api._names()

    def get_obj_pos(self, obj):
        """[x, y, z] (m) of an object's centre; a list of names gives a list.

        The centre is the origin of the object's own frame: a block's or ball's geometric centre;
        a zone's centre (z = half its 1 mm thickness); a bowl's axis at mid-height of its wall; a
        fixture's local-frame origin, the centre of its slot (0, 0, 0) at the height of a small
        block's centre standing there (not the middle of its L), so slot (u, v) is this point
        plus (u, v) turned by the fixture's yaw.
        """
        if isinstance(obj, (list, tuple, np.ndarray)):
            return [self.get_obj_pos(o) for o in obj]
        return [Coordinate(v) for v in self._api._pos(self._api._resolve(obj).obj_id)]

    def get_obj_rot(self, obj):
        """Orientation quaternion (x, y, z, w) of an object; a list of names gives a list.

        Objects start at random yaws (about z); an upright object's yaw is 2 atan2(z, w)."""
        if isinstance(obj, (list, tuple, np.ndarray)):
            return [self.get_obj_rot(o) for o in obj]
        return [Coordinate(v) for v in self._api._quat_xyzw(self._api._resolve(obj).obj_id)]

    def get_bbox(self, obj):
        """World axis-aligned box (xmin, ymin, zmin, xmax, ymax, zmax) (m), the thesis's box, not
        the sizes CapRavens' code returned (sizes are xmax − xmin, ...).  A list of names gives the
        box of its first object, as CapRavens' did: its examples pass a list of like blocks to ask
        one block's box.

        The box around the object as it is turned now: a square zone of side s turned by yaw θ
        spans s (|cos θ| + |sin θ|) in x and in y, more than s; its side is the box width divided
        by that factor (yaw from :meth:`get_obj_rot`).  Round objects (bowls, balls) give the box
        of their disc whatever their yaw."""
        if isinstance(obj, (list, tuple, np.ndarray)):
            if len(obj) == 0:
                raise ValueError("get_bbox needs an object name (a list gives its first object's box), got []")
            return self.get_bbox(obj[0])
        o = self._api._resolve(obj)
        lo, hi = self._api._world.aabb(o.obj_id)
        if o.kind in ROUND_KINDS:  # the geoms' boxes turn with the yaw, the disc does not
            c, r = self._api._pos(o.obj_id), o.half_extents[0]
            lo[:2], hi[:2] = c[:2] - r, c[:2] + r
        return tuple(float(v) for v in (*lo, *hi))

    def get_obj_pos_dict(self) -> dict[str, tuple[list[float], list[float]]]:
        """{name: ([x, y, z], [roll, pitch, yaw])} for every object (m, rad; Euler XYZ)."""
        api = self._api
        return {o.name: ([float(v) for v in api._pos(o.obj_id)], quat_euler_xyz(wxyz(api._quat_xyzw(o.obj_id))))
                for o in api._objects()}

    def get_obj_positions_np(self, names) -> np.ndarray:
        """(n, 3) array of object centres (m)."""
        names = [names] if isinstance(names, (str, int)) else list(names)
        return np.array([self.get_obj_pos(n) for n in names], float).reshape(-1, 3)

    def get_obj_rotations_np(self, names) -> np.ndarray:
        """(n, 4) array of object quaternions (x, y, z, w)."""
        names = [names] if isinstance(names, (str, int)) else list(names)
        return np.array([self.get_obj_rot(n) for n in names], float).reshape(-1, 4)

    def get_color(self, obj) -> str:
        """The colour name of an object ("red", "blue", ...)."""
        return self._api._resolve(obj).color

    def denormalize(self, pos):
        """Normalised [u, v] (u left→right, v bottom→top, both in [0, 1]) → world [x, y]:
        x = 0.75 − 0.5 v, y = −0.5 + u.  A third value (z) is passed through; a list of
        points gives a list."""
        arr = np.asarray(pos, float)
        if arr.ndim == 2:
            return [self.denormalize(p) for p in arr]
        if arr.ndim != 1 or len(arr) not in (2, 3):
            raise ValueError(f"denormalize expects [u, v] or [u, v, z], got {_summary(pos, 80)}")
        x, y = denormalize_uv(arr[0], arr[1])
        return [x, y] + ([float(arr[2])] if len(arr) == 3 else [])

    def get_corner_name(self, pos) -> str:
        """Name of the workspace corner nearest to a position ("top left corner", ...)."""
        p = self._api._xy(pos)
        corners = np.array([denormalize_uv(u, v) for u, v in _CORNERS_UV])
        return CORNER_NAMES[int(np.argmin(np.hypot(*(corners - p).T)))]

    def get_side_name(self, pos) -> str:
        """Name of the workspace side nearest to a position ("top side", "right side", ...)."""
        p = self._api._xy(pos)
        sides = np.array([denormalize_uv(u, v) for u, v in _SIDES_UV])
        return SIDE_NAMES[int(np.argmin(np.hypot(*(sides - p).T)))]

    def is_target_occupied(self, targ, r: float = 0.02) -> list[str]:
        """Names of the objects occupying a target.

        ``targ`` a position ([x, y], [x, y, z] or (position, quaternion)): every object whose
        footprint lies within ``r`` m of its xy.  ``targ`` a name: every other object whose
        footprint overlaps that object's footprint (e.g. blocks in a zone, or the zone under a
        block and whatever is stacked on it).  ``targ`` a list of positions or poses: the objects
        occupying any of them, each once.  Zones, bowls and the like count as objects.
        """
        return self._api._occupied(targ, float(r))

    def get_random_free_pos(self, targ=None, area=None, r: float = FREE_CLEARANCE, search_area=None) -> list[float]:
        """A random free position [x, y, 0.0] (m) on the table.

        ``area`` = (xmin, ymin, xmax, ymax), default the reachable workspace; the returned
        centre keeps ``r`` from the area border when the area allows.  Free = at least ``r``
        m from every object's footprint (the default 0.045 fits a big block at any yaw) and
        not occupying ``targ`` (names, positions or poses to keep ``2 r`` from — objects are
        avoided anyway).  Raises ValueError when nothing is free.
        """
        return self._api._free_pos(targ, search_area if area is None else area, float(r))

    def put_first_on_second(self, obj, target) -> None:
        """One pick-and-place of ``obj`` (a name; fixed objects cannot be picked).

        Objects start at random yaws; where the object goes and the yaw it ends with follow
        from the form of ``target``:

        * a name → on that object's real top (a zone: at its centre, on the table or on what is
          stacked there; a bowl: inside, on its floor), turned like the block or zone it goes
          on; in a bowl, on a ball or a fixture it keeps its yaw;
        * [x, y] → centred at that point, resting on whatever is there, aligned with the world
          axes (yaw 0: the pose ([x, y, z], (0, 0, 0, 1)), as in CapRavens);
        * [x, y, z] → the same, with z the height of the object's centre where it is let go: the
          arm lowers it to z, or until it touches something first, and releases it; a z below
          the resting height there counts as that height, a z above it drops the object;
        * ([x, y] or [x, y, z], quaternion xyzw) → as above, turned to the quaternion's yaw.

        Blocks are symmetric every 90°, so a block turns by at most 45°.
        Raises ValueError for bad arguments and RuntimeError when the robot fails.
        """
        self._api._put(obj, target)

    def stack_objects_in_order(self, object_names, targ=None) -> None:
        """Stack ``object_names`` bottom ([0]) to top; [0] goes on ``targ`` when given, otherwise
        it stays where it is.  Each next object goes on the previous one's top.  (The parameter
        keeps CapRavens' name, so ``stack_objects_in_order(object_names=...)`` runs as written.)"""
        names = object_names
        if isinstance(names, (str, int)):
            names = [names]
        names = list(names)
        if not names:
            return
        put = self._logged["put_first_on_second"]  # each step appears in the call log
        if targ is not None:
            put(names[0], targ)
        for lower, upper in zip(names, names[1:]):
            put(upper, lower)

    def say(self, msg) -> None:
        """Record a message in the episode log."""
        text = str(msg)
        self._api.messages.append(text)
        self._api._ctx.recorder.text("planner/say", text, self._api._world.time)


API_FUNCTIONS: tuple[str, ...] = (
    "get_obj_names",
    "get_obj_pos",
    "get_obj_rot",
    "get_bbox",
    "get_obj_pos_dict",
    "denormalize",
    "denormalize_xy",
    "denormalize_bbox",
    "is_target_occupied",
    "get_random_free_pos",
    "put_first_on_second",
    "stack_objects_in_order",
    "say",
    "is_obj_visible",
    "bbox_contains_pt",
    "get_obj_positions_np",
    "get_obj_rotations_np",
    "get_corner_name",
    "get_side_name",
    "get_color",
    "reset",
)
"""The names of the planner API functions (methods of :class:`PlanFunctions`), in the order
:meth:`PlannerAPI.functions` returns them."""


# the geometry constants are re-exported: callers and benchmarks import them from here
__all__ = ["API_FUNCTIONS", "FREE_CLEARANCE", "FREE_GRID_STEP", "PlanFunctions", "PlannerAPI", "REACH_RADIUS",
           "denormalize_uv"]
