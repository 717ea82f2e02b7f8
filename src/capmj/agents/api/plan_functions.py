"""The planner API functions, one method each: their names, signatures and docstrings are the API
the prompts document (``prompts/planner.py``; the docstrings are the full statement).

:class:`PlanFunctions` works over a :class:`~capmj.agents.api.planner_api.PlannerAPI` (through its public
interface, :class:`~capmj.agents.api.interface.PlannerInterface`), which resolves names, checks
arguments and logs each call; the geometry is :mod:`capmj.agents.api.footprints`.  Kept apart
from the facade so that the list of what plan code may call (:data:`API_FUNCTIONS`) and what each
call promises read in one place.
"""

from __future__ import annotations

from typing import Any, Callable, Mapping

import numpy as np

from capmj.agents.api.values import Coordinate, denormalize_uv
from capmj.agents.api.values import summary as _summary
from capmj.agents.api.capravens import CapRavensFunctions
from capmj.agents.api.footprints import FREE_CLEARANCE
from capmj.agents.api.interface import PlannerInterface
from capmj.agents.sandbox.sizes import capped_text
from capmj.errors import TextBudgetExceeded
from capmj.sim.footprint import ROUND_KINDS
from capmj.sim.pose import quat_euler_xyz, wxyz


CORNER_NAMES = ("top left corner", "top right corner", "bottom left corner", "bottom right corner")
SIDE_NAMES = ("top side", "right side", "bottom side", "left side")

# The types the functions take (their JSON forms in agents/api/tool_schemas): a name or an obj_id,
# a position [x, y] or [x, y, z], a pose (position, quaternion xyzw).
Name = str | int
Position = list[float]
Pose = tuple[Position, list[float]]
Place = Name | Position | Pose
_CORNERS_UV = ((0.0, 1.0), (1.0, 1.0), (0.0, 0.0), (1.0, 0.0))
_SIDES_UV = ((0.5, 1.0), (1.0, 0.5), (0.5, 0.0), (0.0, 0.5))


class PlanFunctions(CapRavensFunctions):
    """The planner API functions of one episode, one method each, over a :class:`PlannerAPI`.

    The methods named in :data:`API_FUNCTIONS` are what plan code calls: their names, signatures
    and docstrings are the API the prompts document.  :meth:`PlannerAPI.functions` hands them out
    wrapped for the call log; a method calling another calls it unlogged (``get_obj_pos`` of a list
    is one logged call), except that :meth:`stack_objects_in_order` logs each step it takes
    (through the logged functions given to :meth:`use_logged`).  Names are resolved, arguments
    checked and logged by the :class:`PlannerAPI`, and the geometry is :mod:`capmj.agents.api.footprints`.
    """

    def __init__(self, api: PlannerInterface) -> None:
        self._api = api
        self._logged: Mapping[str, Callable[..., Any]] = {}

    def use_logged(self, logged: Mapping[str, Callable[..., Any]]) -> None:
        """The logged versions of these functions, for the ones that call others as steps."""
        self._logged = logged

    def get_obj_names(self) -> list[str]:
        """Names of every object in the scene (read from the live world)."""
        return self._api.object_names()

    def get_obj_pos(self, obj: Name | list[Name]) -> list[Any]:
        """[x, y, z] (m) of an object's centre; a list of names gives a list.

        The centre is the origin of the object's own frame: a block's or ball's geometric centre;
        a zone's centre (z = half its 1 mm thickness); a bowl's axis at mid-height of its wall; a
        fixture's local-frame origin, the centre of its slot (0, 0, 0) at the height of a small
        block's centre standing there (not the middle of its L), so slot (u, v) is this point
        plus (u, v) turned by the fixture's yaw.
        """
        if isinstance(obj, (list, tuple, np.ndarray)):
            return [self.get_obj_pos(o) for o in obj]
        return [Coordinate(v) for v in self._api.position(self._api.resolve(obj).obj_id)]

    def get_obj_rot(self, obj: Name | list[Name]) -> list[Any]:
        """Orientation quaternion (x, y, z, w) of an object; a list of names gives a list.

        Objects start at random yaws (about z); an upright object's yaw is 2 atan2(z, w)."""
        if isinstance(obj, (list, tuple, np.ndarray)):
            return [self.get_obj_rot(o) for o in obj]
        return [Coordinate(v) for v in self._api.quat_xyzw(self._api.resolve(obj).obj_id)]

    def get_bbox(self, obj: Name | list[Name]) -> tuple[float, ...]:
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
        o = self._api.resolve(obj)
        lo, hi = self._api.world.aabb(o.obj_id)
        if o.kind in ROUND_KINDS:  # the geoms' boxes turn with the yaw, the disc does not
            c, r = self._api.position(o.obj_id), o.half_extents[0]
            lo[:2], hi[:2] = c[:2] - r, c[:2] + r
        return tuple(float(v) for v in (*lo, *hi))

    def get_obj_pos_dict(self) -> dict[str, tuple[list[float], list[float]]]:
        """{name: ([x, y, z], [roll, pitch, yaw])} for every object (m, rad; Euler XYZ)."""
        api = self._api
        return {o.name: ([float(v) for v in api.position(o.obj_id)], quat_euler_xyz(wxyz(api.quat_xyzw(o.obj_id))))
                for o in api.objects()}

    def get_obj_positions_np(self, names: Name | list[Name]) -> np.ndarray:
        """(n, 3) array of object centres (m)."""
        names = [names] if isinstance(names, (str, int)) else list(names)
        return np.array([self.get_obj_pos(n) for n in names], float).reshape(-1, 3)

    def get_obj_rotations_np(self, names: Name | list[Name]) -> np.ndarray:
        """(n, 4) array of object quaternions (x, y, z, w)."""
        names = [names] if isinstance(names, (str, int)) else list(names)
        return np.array([self.get_obj_rot(n) for n in names], float).reshape(-1, 4)

    def get_color(self, obj: Name) -> str:
        """The colour name of an object ("red", "blue", ...)."""
        return self._api.resolve(obj).color

    def denormalize(self, pos: list[float] | list[list[float]]) -> list[Any]:
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

    def get_corner_name(self, pos: Place) -> str:
        """Name of the workspace corner nearest to a position ("top left corner", ...)."""
        p = self._api.xy(pos)
        corners = np.array([denormalize_uv(u, v) for u, v in _CORNERS_UV])
        return CORNER_NAMES[int(np.argmin(np.hypot(*(corners - p).T)))]

    def get_side_name(self, pos: Place) -> str:
        """Name of the workspace side nearest to a position ("top side", "right side", ...)."""
        p = self._api.xy(pos)
        sides = np.array([denormalize_uv(u, v) for u, v in _SIDES_UV])
        return SIDE_NAMES[int(np.argmin(np.hypot(*(sides - p).T)))]

    def is_target_occupied(self, targ: Place | list[Position | Pose], r: float = 0.02) -> list[str]:
        """Names of the objects occupying a target.

        ``targ`` a position ([x, y], [x, y, z] or (position, quaternion)): every object whose
        footprint lies within ``r`` m of its xy.  ``targ`` a name: every other object whose
        footprint overlaps that object's footprint (e.g. blocks in a zone, or the zone under a
        block and whatever is stacked on it).  ``targ`` a list of positions or poses: the objects
        occupying any of them, each once.  Zones, bowls and the like count as objects.
        """
        return self._api.occupied(targ, float(r))

    def get_random_free_pos(self, targ: Place | list[Place] | None = None,
                            area: tuple[float, float, float, float] | None = None, r: float = FREE_CLEARANCE,
                            search_area: tuple[float, float, float, float] | None = None) -> list[float]:
        """A random free position [x, y, 0.0] (m) on the table.

        ``area`` = (xmin, ymin, xmax, ymax), default the reachable workspace; the returned
        centre keeps ``r`` from the area border when the area allows.  Free = at least ``r``
        m from every object's footprint (the default 0.045 fits a big block at any yaw) and
        not occupying ``targ`` (names, positions or poses to keep ``2 r`` from — objects are
        avoided anyway).  Raises ValueError when nothing is free.
        """
        return self._api.free_position(targ, search_area if area is None else area, float(r))

    def put_first_on_second(self, obj: Name | Position, target: Place) -> None:
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
        self._api.put(obj, target)

    def stack_objects_in_order(self, object_names: list[Name] | Name, targ: Place | None = None) -> None:
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

    def say(self, msg: str) -> None:
        """Record a message in the episode log.  The messages of one attempt hold at most
        ``Budget.max_said_chars`` characters together; one that would pass it is refused
        (:class:`~capmj.errors.TextBudgetExceeded`) before its text is made."""
        cap = self._api.ctx.budget.max_said_chars
        text = capped_text(msg, cap - self._api.said_chars)
        if text is None:
            raise TextBudgetExceeded(f"say() would record more than {cap} characters in this attempt "
                                     "(Budget.max_said_chars)")
        self._api.said_chars += len(text)
        self._api.messages.append(text)
        self._api.ctx.recorder.text("planner/say", text, self._api.world.time)


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

