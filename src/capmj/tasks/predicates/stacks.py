"""Stacks: upright objects resting on the table or on each other, and towers built from them.

The spec's stack: xy centres within 0.02 m of the stack axis, the lowest resting on the table (or
a zone), each next one resting on the previous one (z gap = mean of the two heights ± 0.015 m),
none tilted more than 15°.  A toppled or split tower is not a stack.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, Sequence

from capmj.sim.state import SceneState
from capmj.tasks.predicates.containment import in_zone
from capmj.tasks.predicates.labels import short_label
from capmj.tasks.predicates.tolerances import STACK_AXIS_TOL, TILT_TOL, Z_TOL


def toppled(state: SceneState, obj_id: int, max_tilt: float = TILT_TOL) -> bool:
    """Whether the object is tilted more than 15° (``TILT_TOL``) from resting on any face."""
    return state.poses[obj_id].tilt > max_tilt


def resting_on_table(state: SceneState, obj_id: int, tol: float = Z_TOL) -> bool:
    """Whether the centre height is half the object's height ± 0.015 m (on the table or a zone)."""
    return abs(float(state.pos(obj_id)[2]) - state.spec(obj_id).height / 2) <= tol


def resting_on(state: SceneState, upper: int, lower: int, tol: float = Z_TOL) -> bool:
    """Whether ``upper`` sits on ``lower``: z gap = mean of the two heights ± 0.015 m and xy
    centres within 0.02 m (``STACK_AXIS_TOL``)."""
    pu, pl = state.pos(upper), state.pos(lower)
    gap = (state.spec(upper).height + state.spec(lower).height) / 2
    return bool(abs((pu[2] - pl[2]) - gap) <= tol and math.hypot(pu[0] - pl[0], pu[1] - pl[1]) <= STACK_AXIS_TOL)


def find_stack_order(state: SceneState, ids: Iterable[int]) -> list[int]:
    """``ids`` sorted bottom to top by centre height (ties broken by id)."""
    return sorted(ids, key=lambda i: (float(state.pos(i)[2]), i))


def is_stack(state: SceneState, ids_bottom_to_top: Sequence[int]) -> tuple[bool, str]:
    """Whether the objects form one stack in the given order, with a reason when not.

    Tolerances: every xy centre within 0.02 m of the stack axis (the vertical line through the
    lowest object's centre); the lowest resting on the table or a zone (z = half its height ±
    0.015 m); each next resting on the previous one (z gap = mean of the two heights ± 0.015 m);
    none tilted more than 15°.  A single upright object on the table is a stack of one.
    """
    ids = list(ids_bottom_to_top)
    if not ids:
        return False, "no objects to stack"
    for i in ids:
        if toppled(state, i):
            return False, f"{short_label(state.spec(i))} is tilted {math.degrees(state.poses[i].tilt):.0f}° (max 15°)"
    base = state.pos(ids[0])
    if not resting_on_table(state, ids[0]):
        want = state.spec(ids[0]).height / 2
        return False, (f"bottom {short_label(state.spec(ids[0]))} is not on the table "
                       f"(z = {base[2]:.3f} m, expected {want:.3f} ± {Z_TOL})")
    for lower, upper in zip(ids, ids[1:]):
        pu, pl = state.pos(upper), state.pos(lower)
        off = math.hypot(pu[0] - base[0], pu[1] - base[1])
        if off > STACK_AXIS_TOL:
            return False, (f"{short_label(state.spec(upper))} is {off:.3f} m off the stack axis "
                           f"(max {STACK_AXIS_TOL})")
        gap = (state.spec(upper).height + state.spec(lower).height) / 2
        dz = float(pu[2] - pl[2])
        if abs(dz - gap) > Z_TOL:
            return False, (f"{short_label(state.spec(upper))} is not resting on {short_label(state.spec(lower))} "
                           f"(z gap {dz:.3f} m, expected {gap:.3f} ± {Z_TOL})")
    return True, f"{len(ids)} object(s) stacked"


def build_tower(
    state: SceneState,
    ids: Iterable[int],
    zone_id: int | None = None,
    accept=None,
) -> list[int]:
    """The tallest stack (bottom first) that can be formed from ``ids`` as they lie.

    A tower starts with an upright object resting on the table (inside ``zone_id`` when given) and
    grows by objects resting on the current top whose centre is within 0.02 m of the tower axis
    (and in the zone); ``accept(level, obj_id)`` may restrict which object may sit at which level
    (level 0 = bottom).  Used for progress: the result is a valid :func:`is_stack` sequence.
    """
    pool = [i for i in ids if not toppled(state, i) and (zone_id is None or in_zone(state, i, zone_id))]
    best: list[int] = []
    for b in pool:
        if not resting_on_table(state, b) or (accept is not None and not accept(0, b)):
            continue
        tower = [b]
        axis = state.pos(b)[:2]
        left = [i for i in pool if i != b]
        while True:
            top = tower[-1]
            cands = []
            for c in left:
                pc = state.pos(c)
                if math.hypot(pc[0] - axis[0], pc[1] - axis[1]) > STACK_AXIS_TOL:
                    continue
                gap = (state.spec(c).height + state.spec(top).height) / 2
                err = abs(float(pc[2] - state.pos(top)[2]) - gap)
                if err > Z_TOL or (accept is not None and not accept(len(tower), c)):
                    continue
                cands.append((err, c))
            if not cands:
                break
            nxt = min(cands)[1]
            tower.append(nxt)
            left.remove(nxt)
        if len(tower) > len(best):
            best = tower
    return best


@dataclass(frozen=True)
class ZoneStack:
    """The blocks of one zone seen as a stack: ``members`` are the given blocks whose centre is in
    the zone, ``tower`` the tallest valid stack among them (bottom first), ``ok`` whether all
    members form that one stack, ``why`` the reason when not."""

    zone: int
    members: tuple[int, ...]
    tower: tuple[int, ...]
    ok: bool
    why: str


def zone_stacks(state: SceneState, zone_ids: Sequence[int], ids: Iterable[int]) -> list[ZoneStack]:
    """For each zone, whether the blocks of ``ids`` lying in it form exactly one stack.

    A zone with no block is not ok ("empty").  Stack rules are :func:`is_stack`'s (axis 0.02 m,
    z gaps ± 0.015 m, tilt ≤ 15°, the bottom on the table).
    """
    ids = list(ids)
    out = []
    for z in zone_ids:
        members = [i for i in ids if in_zone(state, i, z)]
        tower = build_tower(state, members, z)
        if not members:
            ok, why = False, "empty"
        else:
            ok, why = is_stack(state, find_stack_order(state, members))
            ok = ok and len(tower) == len(members)
            if not ok and len(tower) < len(members) and why.endswith("stacked"):
                why = f"{len(members) - len(tower)} block(s) in the zone are not on its stack"
        out.append(ZoneStack(z, tuple(members), tuple(tower), ok, why))
    return out


__all__ = ["ZoneStack", "build_tower", "find_stack_order", "is_stack", "resting_on", "resting_on_table", "toppled",
           "zone_stacks"]
