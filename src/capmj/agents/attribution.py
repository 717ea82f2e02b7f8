"""Facts an episode records so that a failure can be attributed later (see capmj.bench.failures).

Why here and not in the classifier: the classifier reads only ``episodes.jsonl``, so everything it
needs must be recorded while the episode runs — which program of an attempt failed (the plan or a
helper LMP), whether the exception came out of an API function, the task's predicate on the state
the reporter judged, where the last attempt's pick-and-places left each object and where that
object is at the end, and the final object poses (for exact replays).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from capmj.records import ApiError, Drift

__all__ = ["PLANNER_PROGRAM", "api_error", "failed_program", "final_poses", "placement_drift"]

PLANNER_PROGRAM = "planner"

_NAMED_HELPER = re.compile(r"\bin the code (\w+) wrote\b|\b(parse_function) could not write\b"
                           r"|\bwritten by (parse_function)\b")
"""Errors that name the failed helper program themselves ("in the code parse_obj_name wrote for
this line, line 1: ...")."""


def _core(error: str) -> str:
    """``"PlanError: line 1: SyntaxError: x"`` -> ``"line 1: SyntaxError: x"`` (class prefix dropped)."""
    head, sep, rest = error.partition(": ")
    return rest if sep and head.isidentifier() else error


def failed_program(calls: Iterable[Any], attempt: int, error: str | None) -> str | None:
    """Which program of ``attempt`` failed: ``"planner"`` or the name of a helper LMP.

    An error that names the program ("in the code parse_obj_name wrote ...") decides.  Else: a
    helper's failure reaches the plan as an exception of the API function the plan called, so the
    plan's error text contains the helper's; the helper whose recorded error is contained in the
    attempt's error is the failed program.  Without such a helper, the plan failed.
    """
    if not error:
        return None
    named = _NAMED_HELPER.search(error)
    if named:
        return next(g for g in named.groups() if g)
    for call in reversed(list(calls)):
        get = call.get if isinstance(call, Mapping) else lambda k, c=call: getattr(c, k, None)
        if get("attempt") != attempt or get("lmp") == PLANNER_PROGRAM or not get("error"):
            continue
        if _core(str(get("error"))) in error:
            return str(get("lmp"))
    return PLANNER_PROGRAM


def api_error(error: str | None, api_log: Sequence[Mapping[str, Any]]) -> ApiError | None:
    """The error the last API call raised, when the attempt's ``error`` is that one, else None."""
    last = api_log[-1] if api_log else None
    if error and last is not None and last.get("error") and _core(str(last["error"])) in error:
        return ApiError(last.get("fn"), str(last["error"]))
    return None


def final_poses(world: Any) -> dict[str, tuple[float, ...]]:
    """Every object's final pose ``(x, y, z, qw, qx, qy, qz)`` (full float precision)."""
    out: dict[str, tuple[float, ...]] = {}
    for o in world.objects:
        p = world.pose(o.obj_id)
        out[o.name] = tuple(float(v) for v in (*p.pos, *p.quat))
    return out


def placement_drift(world: Any, placements: Mapping[int, tuple[Any, Any]]) -> Drift:
    """How far each object placed in the last attempt ended from where its primitive put it.

    ``placements`` maps obj_id -> (place target, position right after the primitive settled).
    The drift of an object is the larger of (target -> end) in xy (and z when the target had a
    height) and (position after the primitive -> end).
    """
    names = {o.obj_id: o.name for o in world.objects}
    drifts: dict[str, float] = {}
    for oid, (place, after) in placements.items():
        if oid not in names:
            continue
        end = world.pose(oid).pos
        d = 0.0
        if place is not None:
            dims = 3 if len(place) > 2 and math.isfinite(float(place[2])) else 2
            d = max(d, math.dist([float(v) for v in place[:dims]], end[:dims]))
        if after is not None:
            d = max(d, math.dist([float(v) for v in after], end))
        drifts[names[oid]] = round(d, 6)
    return Drift(max(drifts.values(), default=0.0), drifts)
