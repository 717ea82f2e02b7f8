"""Scene facts capmj computes for a reporter, so that a model only compares them with the goal.

With the thesis's reporter (``parse_completion``) the model has to derive every fact itself —
write code that reads poses, knows a zone's size and a bowl's radius, and tests containment and
stacking.  The ``checked`` reporter prompt (:mod:`capmj.agents.report.checked`) instead shows one
line of *measured* facts per object and asks only whether they match the goal.

Each fact uses capmj's own rule, the one the task predicates use (:mod:`capmj.tasks.predicates`):
a zone holds an object whose centre lies inside the zone's turned square
(:func:`~capmj.tasks.predicates.in_zone`), a bowl one within ``BOWL_TOL`` of its axis and below its
rim (:func:`~capmj.tasks.predicates.in_bowl`), an object rests on another when
:func:`~capmj.tasks.predicates.resting_on` holds, on the table when
:func:`~capmj.tasks.predicates.resting_on_table` does, and is tilted beyond ``TILT_TOL``
(:func:`~capmj.tasks.predicates.toppled`).  The poses come from the planner API the reporter is
given (so with ``--perception rgbd`` they are the perceived ones, as for every other reporter),
the kinds, colours and sizes from the scene's specs.

The module also resolves the names a model writes in ``wrong = [...]`` to real objects
(:func:`resolve_name`): a full name, an ``obj_id N``, or a ``<colour> <kind>`` phrase that names
exactly one object.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from capmj.sim.objects import ObjectSpec
from capmj.sim.pose import wxyz
from capmj.sim.state import Pose, SceneState
from capmj.tasks import predicates as P

__all__ = ["AREAS", "OUTSIDE", "ObjectFacts", "area_of", "facts_text", "resolve_name", "scene_facts", "state_from_api"]


@dataclass(frozen=True)
class ObjectFacts:
    """What capmj measured about one object (names are the planner-facing full names)."""

    name: str
    kind: str
    position: tuple[float, float, float]
    area: str
    """The quadrant of the workspace its centre lies in ("top left", ...)."""
    rests_on: str
    """``"the table"``, another object's name, ``"<bowl name> (inside)"``, or ``"nothing (in the air or leaning)"``."""
    inside: tuple[str, ...]
    """The zones and bowls it is in, by the tasks' containment rule."""
    tilt_deg: float
    holds: tuple[str, ...] = ()
    """For a zone or bowl: the movable objects inside it."""


def state_from_api(api: Mapping[str, Callable[..., Any]], objects: Sequence[ObjectSpec]) -> SceneState:
    """The scene as the planner API reports it (positions and rotations), with the scene's specs."""
    poses = {o.obj_id: Pose.of(api["get_obj_pos"](o.name), wxyz(api["get_obj_rot"](o.name))) for o in objects}
    return SceneState(tuple(objects), poses)


OUTSIDE = "outside the workspace"
AREAS = (*P.QUADRANTS, OUTSIDE)
"""Every value :func:`area_of` gives."""


def area_of(pos: Any) -> str:
    """The quarter of the workspace ``pos`` lies in ("top left", ...), or :data:`OUTSIDE`."""
    return next((q for q in P.QUADRANTS if P.in_area(pos, q)), OUTSIDE)


def scene_facts(state: SceneState) -> tuple[ObjectFacts, ...]:
    """One :class:`ObjectFacts` per object, in scene order."""
    zones = [o.obj_id for o in state.of_kind("zone")]
    bowls = [o.obj_id for o in state.of_kind("bowl")]
    movable = [o.obj_id for o in state.objects if not o.fixed]
    inside: dict[int, list[int]] = {o.obj_id: [] for o in state.objects}
    for i in movable:
        inside[i] = [z for z in zones if P.in_zone(state, i, z)] + [b for b in bowls if P.in_bowl(state, i, b)]
    out = []
    for spec in state.objects:
        i = spec.obj_id
        x, y, z = (round(float(v), 3) for v in state.pos(i))
        out.append(ObjectFacts(
            name=spec.name, kind=spec.kind, position=(x, y, z),
            area=area_of(state.pos(i)), rests_on=_rests_on(state, i, bowls, movable) if not spec.fixed else "the table",
            inside=tuple(state.spec(c).name for c in inside[i]),
            tilt_deg=round(math.degrees(state.poses[i].tilt), 0),
            holds=tuple(state.spec(m).name for m in movable if i in inside[m])))
    return tuple(out)


def _rests_on(state: SceneState, i: int, bowls: Sequence[int], movable: Sequence[int]) -> str:
    below = [o for o in movable if o != i and P.resting_on(state, i, o)]
    if below:
        return state.spec(max(below, key=lambda o: float(state.pos(o)[2]))).name
    for b in bowls:
        if P.in_bowl(state, i, b):
            return f"{state.spec(b).name} (inside)"
    if P.resting_on_table(state, i):
        return "the table"
    return "nothing (in the air or leaning)"


def facts_text(facts: Sequence[ObjectFacts]) -> str:
    """The facts as the ``checked`` prompt shows them: one line per object."""
    lines = []
    for f in facts:
        x, y, z = f.position
        head = f"- {f.name}: centre [{x:.3f}, {y:.3f}, {z:.3f}], {f.area}"
        if f.kind in ("zone", "bowl"):
            held = ", ".join(f.holds) if f.holds else "nothing"
            lines.append(f"{head}; holds: {held}")
            continue
        inside = ", ".join(f.inside) if f.inside else "no zone or bowl"
        tilt = "upright" if f.tilt_deg <= math.degrees(P.TILT_TOL) else f"TILTED {f.tilt_deg:.0f} deg"
        lines.append(f"{head}; rests on {f.rests_on}; in {inside}; {tilt}")
    return "\n".join(lines)


_OBJ_ID = re.compile(r"obj_id\s*(\d+)")


def resolve_name(name: str, objects: Sequence[ObjectSpec]) -> ObjectSpec | None:
    """The object a model meant by ``name``: its full name (case and spacing ignored), else the one
    with the ``obj_id N`` it quotes, else the only object matching a ``<colour> <kind>`` phrase in
    it; None when it names no real object (or several)."""
    text = " ".join(name.lower().split())
    for o in objects:
        if o.name.lower() == text:
            return o
    m = _OBJ_ID.search(text)
    if m is not None:
        return next((o for o in objects if o.obj_id == int(m.group(1))), None)
    hits = [o for o in objects if re.search(rf"\b{re.escape(o.color)}\s+{re.escape(o.kind)}\b", text)]
    return hits[0] if len(hits) == 1 else None
