"""The measured scene a reporter judges, in the tasks' own terms: facts per object and records.

Every fact uses the rule the task predicates use (:mod:`capmj.tasks.predicates`, its tolerances
only): a zone holds an object whose centre lies inside the zone's turned square
(:func:`~capmj.tasks.predicates.in_zone`), a bowl one within ``BOWL_TOL`` of its axis and below its
rim (:func:`~capmj.tasks.predicates.in_bowl`), an object rests on another when
:func:`~capmj.tasks.predicates.resting_on` holds, on the table when
:func:`~capmj.tasks.predicates.resting_on_table` does, and is tilted beyond ``TILT_TOL``.  The poses
come from the planner API the reporter is given (with ``--perception rgbd`` the perceived ones),
the kinds, colours and sizes from the scene's specs.

- :func:`scene_facts` / :func:`facts_text`: one line of facts per object (the ``checked`` prompt);
- :func:`records`: the same facts as one plain ``dict`` per object (the ``relations`` checks), with
  the keys :data:`RECORD_KEYS`: ``name``, ``kind``, ``color``, ``size`` (blocks; else None), ``area``
  (quarter of the table), ``start_area`` (the quarter it was in when the episode began),
  ``rests_on`` (``"table"``, the full name of the object or bowl it is centred on, or
  ``"nothing"``), ``below`` (the movable objects it rests on, by footprint overlap), ``level`` (1
  on the table, a zone or in a bowl; else one more than the highest object below), ``inside``
  (the zone or bowl it is in, ``""`` for none), ``inside_color``, ``holds`` (zones and bowls: the
  movable objects inside), ``tilted`` and ``centre``; built fresh for every run, so code that
  mutates them cannot change what a later run sees;
- :func:`resolve_name`: the object a model meant by a name it wrote in ``wrong = [...]``.
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

__all__ = ["AREAS", "INVENTORY_KEYS", "OUTSIDE", "RECORD_KEYS", "ObjectFacts", "area_of", "facts_text", "records",
           "records_text", "resolve_name", "scene_facts", "start_areas_of", "state_from_api"]


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


RECORD_KEYS = ("name", "kind", "color", "size", "area", "start_area", "rests_on", "below", "level", "inside", "inside_color",
               "holds", "tilted", "centre")
INVENTORY_KEYS = ("name", "kind", "color", "size")
"""The keys that acting cannot change: what the ``relations`` question shows before the check runs."""
_REST_SUFFIX = " (inside)"
_NOTHING = "nothing (in the air or leaning)"


def _record_rests_on(fact: ObjectFacts) -> str:
    if fact.rests_on == "the table":
        return "table"
    if fact.rests_on == _NOTHING:
        return "nothing"
    return fact.rests_on.removesuffix(_REST_SUFFIX)


def _below(state: SceneState, movable: Sequence[int]) -> dict[int, list[int]]:
    """The movable objects each object rests on, by footprint overlap (:func:`~capmj.tasks.predicates.supporters`):
    a block bridging two or four others (a pyramid's upper layers) rests on all of them."""
    return {o.obj_id: P.supporters(state, o.obj_id, [m for m in movable if m != o.obj_id]) if not o.fixed else []
            for o in state.objects}


def _levels(below: Mapping[int, Sequence[int]]) -> dict[int, int]:
    """1 + the highest level below (1 on the table, a zone or in a bowl); a support loop counts once."""
    out: dict[int, int] = {}

    def level(i: int, seen: frozenset[int]) -> int:
        if i not in out:
            out[i] = 1 + max((level(j, seen | {i}) for j in below[i] if j not in seen), default=0)
        return out[i]

    for i in below:
        level(i, frozenset())
    return out


def records(state: SceneState, start_areas: Mapping[int, str] | None = None) -> list[dict[str, Any]]:
    """One record per object of ``state``, in scene order (:data:`RECORD_KEYS`, see the module docstring)."""
    facts = scene_facts(state)
    below = _below(state, [o.obj_id for o in state.objects if not o.fixed])
    levels = _levels(below)
    colors = {o.name: o.color for o in state.objects}
    out = []
    for spec, f in zip(state.objects, facts):
        container = f.kind in ("zone", "bowl")
        out.append({
            "name": f.name, "kind": f.kind, "color": spec.color, "size": spec.size,
            "area": f.area, "start_area": (start_areas or {}).get(spec.obj_id, f.area),
            "rests_on": _record_rests_on(f), "below": [state.spec(j).name for j in below[spec.obj_id]],
            "level": levels[spec.obj_id],
            "inside": f.inside[0] if f.inside else "", "inside_color": colors[f.inside[0]] if f.inside else "",
            "holds": list(f.holds) if container else [],
            "tilted": f.tilt_deg > math.degrees(P.TILT_TOL), "centre": [round(v, 3) for v in f.position]})
    return out


def records_text(rows: Sequence[Mapping[str, Any]], keys: Sequence[str] = RECORD_KEYS) -> str:
    """``objects = [...]`` with one record per line, as the prompt shows it (``keys``, in their order)."""
    lines = ["objects = ["]
    for r in rows:
        lines.append("    {" + ", ".join(f"{k!r}: {r[k]!r}" for k in keys) + "},")
    lines.append("]")
    return "\n".join(lines)


def start_areas_of(positions: Mapping[int, Sequence[float]]) -> dict[int, str]:
    """``{obj_id: quarter}`` of the positions an episode began with."""
    return {i: area_of(p) for i, p in positions.items()}
