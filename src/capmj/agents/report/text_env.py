"""What the text reporter's checking code finds already defined, so a dropped line cannot break it.

The reporter runs its code in an environment that pre-binds everything the examples of
``prompts/parse_completion.py`` use, computed once from the settled scene it judges, so an answer
that copies an example without its first line (``poses = get_obj_pos_dict()``) or calls a helper
the example defined inline still runs (why: ``docs/judge.md``, "Why each gate exists"):

``poses``          ``{name: ([x, y, z], [roll, pitch, yaw])}`` (= ``get_obj_pos_dict()``); also bound
                   as ``object_positions``, the name CapRavens' checking code reads it under;
                   a near-miss name as key reads its object (:class:`NamedPoses`)
``sizes``          ``{block name: edge length (m)}``
``blocks``, ``zones``, ``bowls``   object names by kind, in scene order
``goal_objects``   ``{'orange zone': 'fixed orange zone with obj_id 1', ...}``: every
                   "<colour> <kind>" phrase of the goal that names exactly one object; each is
                   also bound as a variable ``orange_zone = 'fixed orange zone with obj_id 1'``
``size(name)``     a block's edge length (0.0 for other objects)
``upright(name)``  roll and pitch within ``TILT_TOL`` of a multiple of pi/2
``in_zone(obj, zone)``  centre inside the zone's square, turned with the zone and of its size
                   (:func:`capmj.tasks.predicates.in_square`: the tasks' one rule)
``in_bowl(obj, bowl)``  centre within ``BOWL_TOL`` of the bowl centre in x-y
``on_top(upper, lower)``  centres within ``STACK_AXIS_TOL`` in x-y and resting: z difference = mean
                   of the two sizes +- ``Z_TOL``

The thresholds are the task predicates' tolerances (:mod:`capmj.tasks.predicates`), the ones
``prompts/parse_completion.py`` states to the model.  These are geometric helpers, not the task
predicates: the reporter still has to decide what the goal means.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from capmj.agents.api.names import near_miss, porting_difference
from capmj.sim.objects import BLOCK_SIZES, ObjectSpec
from capmj.tasks.predicates import BOWL_TOL, STACK_AXIS_TOL, TILT_TOL, Z_TOL, in_square

__all__ = ["PREBOUND", "NamedPoses", "goal_objects", "reporter_env"]

PREBOUND = ("poses", "object_positions", "sizes", "blocks", "zones", "bowls", "goal_objects", "size", "upright", "in_zone",
            "in_bowl", "on_top")
"""Names the reporter's code may use without defining them (listed in the repair request), besides
the ``<colour>_<kind>`` variables of the goal's named objects."""


def goal_objects(goal: str, objects: Sequence[Any]) -> dict[str, str]:
    """``{"<colour> <kind>": name}`` for each such phrase in ``goal`` that names exactly one object."""
    text = " ".join(goal.lower().split())
    out: dict[str, str] = {}
    for o in objects:
        phrase = f"{o.color} {o.kind}"
        if phrase in out or not re.search(rf"\b{re.escape(phrase)}s?\b", text):
            continue
        same = [p for p in objects if p.kind == o.kind and p.color == o.color]
        if len(same) == 1:
            out[phrase] = o.name
    return out


class NamedPoses(dict):
    """``poses`` / ``object_positions``: keyed by capmj's names, and a near-miss key reads the one
    object it can only mean, as the API's names do (:func:`capmj.agents.api.names.near_miss`).
    CapRavens' checking code indexes the dict with names such as ``'red block with obj_id 1'``;
    an obj_id 0 or a fixed block is a PortingDifference naming why, anything else a KeyError."""

    def __init__(self, poses: Mapping[str, Any], objects: Sequence[ObjectSpec]) -> None:
        super().__init__(poses)
        self._objects = tuple(objects)

    def __missing__(self, key: Any) -> Any:
        if isinstance(key, str):
            fit = near_miss(key, self._objects)
            if fit is not None and fit.name in self:
                return self[fit.name]
            porting_difference(key, self._objects)
        raise KeyError(key)


def reporter_env(api: Mapping[str, Callable[..., Any]], objects: Sequence[Any], goal: str) -> dict[str, Any]:
    """The pre-bound names (see the module docstring) for the current scene."""
    poses = NamedPoses(api["get_obj_pos_dict"](), [o for o in objects if isinstance(o, ObjectSpec)])
    kinds = {o.name: o.kind for o in objects}
    sizes = {o.name: BLOCK_SIZES[o.size or "small"] for o in objects if o.kind == "block"}
    zone_half = {o.name: o.half_extents[0] for o in objects if o.kind == "zone"}

    def _pos(name: str) -> list[float]:
        if name not in poses:
            raise KeyError(f"unknown object {name!r}; objects: {list(poses)}")
        return poses[name][0]

    def size(name: str) -> float:
        """Edge length (m) of a block; 0.0 for zones, bowls and other objects."""
        _pos(name)
        return sizes.get(name, 0.0)

    def upright(name: str) -> bool:
        """True when the object is not tilted (|roll|, |pitch| within TILT_TOL of a multiple of pi/2)."""
        _pos(name)
        quarter = math.pi / 2
        return all(min(abs(a) % quarter, quarter - abs(a) % quarter) < TILT_TOL for a in poses[name][1][:2])

    def in_zone(obj: str, zone: str) -> bool:
        """True when ``obj``'s centre lies inside ``zone``'s square (its yaw and size honoured)."""
        centre = _pos(zone)
        if zone not in zone_half:
            raise ValueError(f"{zone!r} is not a zone; zones: {list(zone_half)}")
        return in_square(_pos(obj), centre, poses[zone][1][2], zone_half[zone])

    def in_bowl(obj: str, bowl: str) -> bool:
        """True when ``obj``'s centre lies within BOWL_TOL of ``bowl``'s centre in x-y."""
        (x, y, _), (bx, by, _) = _pos(obj), _pos(bowl)
        return math.hypot(x - bx, y - by) < BOWL_TOL

    def on_top(upper: str, lower: str) -> bool:
        """True when ``upper`` rests directly on ``lower`` (aligned in x-y, touching in z)."""
        (x1, y1, z1), (x0, y0, z0) = _pos(upper), _pos(lower)
        gap = (size(upper) + size(lower)) / 2
        return math.hypot(x1 - x0, y1 - y0) < STACK_AXIS_TOL and abs(z1 - z0 - gap) < Z_TOL

    named = goal_objects(goal, objects)
    env: dict[str, Any] = {phrase.replace(" ", "_"): name for phrase, name in named.items()
                           if phrase.replace(" ", "_").isidentifier()}
    env.update({
        "poses": poses,
        "object_positions": poses,
        "sizes": sizes,
        "blocks": [n for n in poses if kinds.get(n) == "block"],
        "zones": [n for n in poses if kinds.get(n) == "zone"],
        "bowls": [n for n in poses if kinds.get(n) == "bowl"],
        "goal_objects": named,
        "size": size,
        "upright": upright,
        "in_zone": in_zone,
        "in_bowl": in_bowl,
        "on_top": on_top,
    })
    return env
