"""The measured scene as Python records, for the ``records`` reporter's checking code.

:mod:`capmj.agents.report.scene_facts` measures each object with the tasks' own rules; this module turns
those facts into one plain ``dict`` per object, the shape a code model reads and filters without
help.  The records are built fresh for every run of checking code, so code that mutates them cannot
change what a later run sees.

Keys (``RECORD_KEYS``, documented to the model in ``prompts/reporter_records.py``):
``name``, ``kind``, ``color``, ``size`` (blocks; else None), ``area`` (quarter of the table),
``start_area`` (the quarter it was in when the episode began), ``rests_on`` (``"table"``, the full
name of the object or bowl it is centred on, or ``"nothing"``), ``below`` (the movable objects it
rests on, by footprint overlap: a pyramid's upper blocks rest on several), ``level`` (1 on the
table, a zone or in a bowl; else one more than the highest object below), ``inside`` (the zone or
bowl it is in, ``""`` for none: a string, so ``b["inside"] != zone["name"]`` needs no guard),
``inside_color`` (its colour, or ``""``), ``holds`` (for zones and bowls: the movable objects
inside), ``tilted`` and ``centre`` ([x, y, z], m).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from capmj.agents.report.scene_facts import ObjectFacts, area_of, scene_facts
from capmj.sim.state import SceneState
from capmj.tasks import predicates as P

__all__ = ["INVENTORY_KEYS", "RECORD_KEYS", "records", "records_text", "start_areas_of"]

RECORD_KEYS = ("name", "kind", "color", "size", "area", "start_area", "rests_on", "below", "level", "inside", "inside_color",
               "holds", "tilted", "centre")
INVENTORY_KEYS = ("name", "kind", "color", "size")
"""The keys that acting cannot change: what the ``goalcheck`` reporter shows before the check runs."""
_REST_SUFFIX = " (inside)"
_NOTHING = "nothing (in the air or leaning)"


def _rests_on(fact: ObjectFacts) -> str:
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
    """One record per object of ``state``, in scene order (see the module docstring for the keys)."""
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
            "rests_on": _rests_on(f), "below": [state.spec(j).name for j in below[spec.obj_id]],
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
