"""Code shared by the benchmark task modules: stack goals and checks, labels, solved states."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Iterable, Sequence

import numpy as np

from capmj.sim.objects import ObjectSpec
from capmj.sim.pose import yaw_quat
from capmj.sim.state import Pose, SceneState
from capmj.tasks import predicates as P
from capmj.tasks.builtin import BENCHMARK_TAG, EXTENDED_TAG
from capmj.tasks.protocol import OracleGoal, Scene, Target, Verdict

BENCHMARK = frozenset({BENCHMARK_TAG})
EXTENDED = frozenset({EXTENDED_TAG})
"""Tag of the extended tasks 1–10 (thesis Table 5.3, written by hand): unseen by the planner's few-shot prompt."""


def label(spec: ObjectSpec) -> str:
    """Diagnostic name of an object, e.g. ``"small red block 3"``."""
    return P.short_label(spec)


def start_positions(objects: Iterable[ObjectSpec]) -> dict[str, list[float]]:
    """JSON-friendly ``{str(id): [x, y, z]}`` of the given objects' spawn positions."""
    return {str(o.obj_id): [float(v) for v in o.pos] for o in objects}


def shuffled(rng: np.random.Generator, items: Sequence) -> list:
    """``items`` in a random order drawn from ``rng``."""
    return [items[int(i)] for i in rng.permutation(len(items))]


# --------------------------------------------------------------------------------------- stacks
def stack_targets(zone: ObjectSpec, blocks_bottom_to_top: Sequence[ObjectSpec]) -> list[Target]:
    """Centre targets of a stack at the zone centre: z = heights below + own half height."""
    out, z = [], 0.0
    for b in blocks_bottom_to_top:
        out.append(Target((float(zone.pos[0]), float(zone.pos[1]), z + b.height / 2), None))
        z += b.height
    return out


def stack_goals(scene: Scene, zone_id: int, ids_bottom_to_top: Sequence[int]) -> list[OracleGoal]:
    """One pose goal per level, bottom first: block ``ids[i]`` to level ``i`` above the zone
    centre (plane tolerance 0.01 m, vertical 0.015 m in the reward)."""
    blocks = [scene.by_id(i) for i in ids_bottom_to_top]
    targets = stack_targets(scene.by_id(zone_id), blocks)
    return [OracleGoal(objects=(b.obj_id,), targets=(t,), matches=((1,),), metric="pose", tolerance=P.PLANE_TOL)
            for b, t in zip(blocks, targets)]


@dataclass
class StackReport:
    """How far a set of blocks is from one stack in a zone."""

    ok: bool
    tower: list[int]
    diagnostics: list[str] = field(default_factory=list)


def check_stack(
    state: SceneState,
    ids: Sequence[int],
    zone_id: int,
    accept: Callable[[int, int], bool] | None = None,
    what: str = "blocks",
) -> StackReport:
    """Do ``ids`` form one stack inside the zone?  ``accept(level, id)`` adds an order rule.

    Success needs :func:`predicates.is_stack` on the blocks sorted by height, every block in the
    zone, and (with ``accept``) every level accepted.  The report's ``tower`` is the tallest valid
    partial stack (for progress); diagnostics name each block that is not on it and why.
    """
    zone = state.spec(zone_id)
    zname = f"{zone.color} zone {zone_id}"
    ids = list(ids)
    tower = P.build_tower(state, ids, zone_id, accept)
    order = P.find_stack_order(state, ids)
    ok, why = P.is_stack(state, order)
    in_z = all(P.in_zone(state, i, zone_id) for i in ids)
    acc = accept is None or all(accept(k, i) for k, i in enumerate(order))
    success = bool(ids) and ok and in_z and acc and len(tower) == len(ids)
    diags: list[str] = []
    if success:
        diags.append(f"all {len(ids)} {what} stacked in the {zname}")
        return StackReport(True, tower, diags)
    diags.append(f"{len(tower)} of {len(ids)} {what} form a valid stack in the {zname}")
    for i in ids:
        if i in tower:
            continue
        s = state.spec(i)
        if P.toppled(state, i):
            diags.append(f"{label(s)} is tilted {math.degrees(state.poses[i].tilt):.0f}° (max 15°)")
        elif not P.in_zone(state, i, zone_id):
            diags.append(f"{label(s)} is not in the {zname} "
                         f"({P.zone_outside_distance(state, i, zone_id):.3f} m outside)")
        else:
            diags.append(f"{label(s)} is in the {zname} but not on the stack (z = {state.pos(i)[2]:.3f} m)")
    if not ok and len(tower) == len(ids):
        diags.append(why)
    if ok and not acc:
        diags.append("the stack's order is wrong")
    return StackReport(False, tower, diags)


def exclusive_zone(state: SceneState, zone_id: int, allowed: Iterable[int]) -> tuple[bool, list[str]]:
    """Whether no block other than ``allowed`` has its centre in the zone; diagnostics name them."""
    allowed = set(allowed)
    extra = [i for i in P.objects_in_zone(state, zone_id) if i not in allowed]
    z = state.spec(zone_id)
    return (not extra, [f"{label(state.spec(i))} must not be in the {z.color} zone {zone_id}" for i in extra])


def verdict(units_met: float, units_total: float, success: bool, diagnostics: Iterable[str]) -> Verdict:
    """A verdict with progress = share of condition units met, clipped to [0, 1]."""
    prog = 1.0 if success else (min(1.0, max(0.0, units_met / units_total)) if units_total else 0.0)
    if not success:
        prog = min(prog, 0.99)
    return Verdict(bool(success), float(prog), tuple(diagnostics))


# --------------------------------------------------------------------------------------- solutions
def solved_state(scene: Scene, goals: Sequence[OracleGoal]) -> SceneState:
    """The final state an ideal oracle reaches: every goal object exactly at its assigned target.

    Goals are taken in order; each object goes to the first target it matches that no earlier
    object took (unless ``replace``).  Objects in no goal stay at their spawn pose.
    """
    poses: dict[int, Pose] = dict(SceneState.from_specs(scene.objects).poses)
    for g in goals:
        taken: set[int] = set()
        for i, oid in enumerate(g.objects):
            for j, t in enumerate(g.targets):
                if g.matches[i][j] and (g.replace or j not in taken):
                    taken.add(j)
                    yaw = t.yaw if t.yaw is not None else scene.by_id(oid).yaw
                    poses[oid] = Pose.of(t.pos, yaw_quat(yaw))
                    break
    return SceneState(tuple(scene.objects), poses)


class BenchTask:
    """Small base for the benchmark tasks: name, tags, and a readable ``repr``."""

    name: str = ""
    tags: frozenset[str] = BENCHMARK

    def __repr__(self) -> str:
        return f"<task {self.name}>"


class SelectedStackTask(BenchTask):
    """Goals and verdict shared by tasks that stack a selection of blocks in one zone (D, E).

    ``scene.info`` holds ``zone`` and ``selected``: the selected blocks must form one stack in
    the zone, and no other block may be in it.
    """

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        return stack_goals(scene, scene.info["zone"], scene.info["selected"])

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        sel, zone = scene.info["selected"], scene.info["zone"]
        rep = check_stack(state, sel, zone, what="selected blocks")
        clean, extra = exclusive_zone(state, zone, sel)
        return verdict(len(rep.tower) + clean, len(sel) + 1, rep.ok and clean, rep.diagnostics + extra)


__all__ = [
    "BENCHMARK", "BenchTask", "EXTENDED", "SelectedStackTask", "StackReport", "check_stack", "exclusive_zone", "label", "shuffled",
    "solved_state", "stack_goals", "stack_targets", "start_positions", "verdict",
]
