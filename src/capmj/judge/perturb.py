"""Perturbations of a solved state: candidate layouts that should break one success condition.

Each function proposes layouts (a :class:`Proposal`) from the settled oracle state; none of them
decides a label.  The set builder (:mod:`capmj.judge.judgeset`) realises every proposal in MuJoCo,
settles it and keeps it only when the task predicate agrees with the intended label and the
objects that were not moved stayed where they were — so a proposal that happens not to matter for
a task (swapping two colours in a task that ignores colour) is simply not kept.

Only *goal objects* (those the task's oracle goals place) are perturbed, and only ones nothing
rests on, so a placement never leaves a block floating.  All randomness comes from the generator
passed in (derived from task, seed and kind), so the same (task, seed) gives the same proposals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Iterator, Sequence

import numpy as np

from capmj.sim.objects import BOWL_FLOOR, BOWL_HEIGHT, ObjectSpec
from capmj.sim.pose import yaw_quat
from capmj.sim.state import Pose, SceneState
from capmj.tasks import predicates as P
from capmj.tasks.spawn import GAP, SPAWN_BOUNDS, centre_bounds

__all__ = ["MAX_SHIFT", "Proposal", "displaced", "free_spot", "near_tolerance", "swapped", "threshold", "toppled",
           "unstacked", "wrong_bowl"]

Layout = dict[int, Pose]
SPOT_TRIES = 400
"""Random table positions tried for one displaced object before giving up."""
MAX_SHIFT = 0.1
"""Largest shift (m) searched for a tolerance's edge; an object still passing this far off has none."""
TOWER_RADIUS = 0.08
"""Elevated objects within this xy distance (m) of the highest one belong to its tower."""
TOPPLE_RADIUS = 0.25
"""A toppled tower's blocks land within this distance (m) of where they stood (plus
``TOPPLE_PER_BLOCK`` per block: a pyramid of 14 blocks needs more room than a stack of 3)."""
TOPPLE_PER_BLOCK = 0.015


@dataclass(frozen=True)
class Proposal:
    """A candidate layout: what was done (``detail``), which objects moved, where they were put."""

    layout: Layout
    moved: tuple[int, ...]
    detail: str


def _label(spec: ObjectSpec) -> str:
    return P.short_label(spec)


def _xy(pose: Pose) -> np.ndarray:
    return np.asarray(pose.pos[:2], dtype=float)


def supports(state: SceneState, obj_id: int, movable: Sequence[int]) -> bool:
    """Whether another movable object rests on (or leans over) ``obj_id``."""
    me, spec = state.pos(obj_id), state.spec(obj_id)
    for o in movable:
        if o == obj_id:
            continue
        p, other = state.pos(o), state.spec(o)
        if p[2] > me[2] + spec.height / 4 and math.hypot(*(p[:2] - me[:2])) < (spec.footprint_radius
                                                                           + other.footprint_radius) * 0.9:
            return True
    return False


def elevated(state: SceneState, obj_id: int) -> bool:
    """Whether the object does not rest on the table (it sits on another object or in a bowl)."""
    return not P.resting_on_table(state, obj_id)


def free_spot(state: SceneState, obj_id: int, rng: np.random.Generator, *, near: np.ndarray | None = None,
              radius: float = math.inf, avoid: Sequence[tuple[np.ndarray, float]] = (),
              ignore: Sequence[int] = ()) -> np.ndarray | None:
    """A random xy on the table where ``obj_id``'s footprint keeps ``GAP`` from every other object
    (zones included: a block dropped in another zone would test that zone, not the displacement),
    optionally within ``radius`` of ``near`` and ignoring the objects ``ignore`` (those that move
    too); None when ``SPOT_TRIES`` draws find none."""
    spec = state.spec(obj_id)
    b = centre_bounds(spec.footprint_radius, SPAWN_BOUNDS)
    others = [(state.pos(o.obj_id)[:2], o.footprint_radius) for o in state.objects
              if o.obj_id != obj_id and o.obj_id not in ignore]
    others += [(np.asarray(c, float)[:2], float(r)) for c, r in avoid]
    for _ in range(SPOT_TRIES):
        xy = np.array([rng.uniform(b.xmin, b.xmax), rng.uniform(b.ymin, b.ymax)])
        if near is not None and math.hypot(*(xy - near[:2])) > radius:
            continue
        if all(math.hypot(*(xy - c)) >= r + spec.footprint_radius + GAP for c, r in others):
            return xy
    return None


def _on_table(spec: ObjectSpec, xy: np.ndarray, yaw: float) -> Pose:
    return Pose.of((float(xy[0]), float(xy[1]), spec.height / 2 + 0.001), yaw_quat(float(yaw)))


def _base(state: SceneState, movable: Sequence[int]) -> Layout:
    return {i: state.poses[i] for i in movable}


def _candidates(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int], rng: np.random.Generator,
                keep: Callable[[int], bool]) -> list[int]:
    """Goal objects nothing rests on that satisfy ``keep``, in a random order."""
    ids = [i for i in goal_ids if i in movable and not supports(state, i, movable) and keep(i)]
    return [ids[int(k)] for k in rng.permutation(len(ids))]


# ------------------------------------------------------------------------------------ negatives
def displaced(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int],
              rng: np.random.Generator) -> Iterator[Proposal]:
    """One goal object resting on the table moved to a free spot elsewhere on the table."""
    yield from _moved_away(state, goal_ids, movable, rng, lambda i: not elevated(state, i), "moved")


def unstacked(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int],
              rng: np.random.Generator) -> Iterator[Proposal]:
    """The top object of a stack or layer (or one in a bowl) taken off and put on the table."""
    yield from _moved_away(state, goal_ids, movable, rng, lambda i: elevated(state, i), "taken off and put")


def _moved_away(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int], rng: np.random.Generator,
                keep: Callable[[int], bool], verb: str) -> Iterator[Proposal]:
    for i in _candidates(state, goal_ids, movable, rng, keep):
        xy = free_spot(state, i, rng)
        if xy is None:
            continue
        layout = _base(state, movable)
        layout[i] = _on_table(state.spec(i), xy, state.poses[i].yaw)
        yield Proposal(layout, (i,), f"{_label(state.spec(i))} {verb} at ({xy[0]:.3f}, {xy[1]:.3f})")


def toppled(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int],
            rng: np.random.Generator) -> Iterator[Proposal]:
    """A tower knocked over: the goal objects of the highest stack or structure (every goal object
    within ``TOWER_RADIUS`` of the highest one in xy, its base included) lie on the table around
    where it stood (random spots within ``TOPPLE_RADIUS``, random yaw)."""
    bowls = [b.obj_id for b in state.of_kind("bowl")]
    ids = [i for i in goal_ids if i in movable and not any(P.in_bowl(state, i, b) for b in bowls)]
    up = [i for i in ids if elevated(state, i)]
    if not up:
        return
    top = max(up, key=lambda i: (float(state.pos(i)[2]), i))
    tower = sorted(i for i in ids if math.hypot(*(state.pos(i)[:2] - state.pos(top)[:2])) <= TOWER_RADIUS)
    for _ in range(3):
        layout = _base(state, movable)
        placed: list[tuple[np.ndarray, float]] = []
        for i in tower:
            xy = free_spot(state, i, rng, near=state.pos(top), radius=TOPPLE_RADIUS + TOPPLE_PER_BLOCK * len(tower),
                           avoid=placed,
                           ignore=tower)
            if xy is None:
                break
            placed.append((xy, state.spec(i).footprint_radius))
            layout[i] = _on_table(state.spec(i), xy, rng.uniform(-math.pi / 4, math.pi / 4))
        else:
            names = ", ".join(_label(state.spec(i)) for i in tower)
            yield Proposal(layout, tuple(tower), f"tower knocked over: {names} lie on the table around it")


def swapped(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int],
            rng: np.random.Generator) -> Iterator[Proposal]:
    """Two goal objects of the same shape and different colours trade places (e.g. two colours of
    an alternating stack, or two blocks in each other's bowl)."""
    ids = [i for i in goal_ids if i in movable]
    pairs = [(a, b) for k, a in enumerate(ids) for b in ids[k + 1:]
             if state.spec(a).half_extents == state.spec(b).half_extents and state.spec(a).color != state.spec(b).color]
    for k in rng.permutation(len(pairs)):
        a, b = pairs[int(k)]
        layout = _base(state, movable)
        pa, pb = state.poses[a], state.poses[b]
        lift = (0.0, 0.0, 0.001)
        layout[a] = Pose.of(tuple(np.add(pb.pos, lift)), pa.quat)
        layout[b] = Pose.of(tuple(np.add(pa.pos, lift)), pb.quat)
        yield Proposal(layout, (a, b), f"{_label(state.spec(a))} and {_label(state.spec(b))} swapped places")


def wrong_bowl(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int],
               rng: np.random.Generator) -> Iterator[Proposal]:
    """A goal object that is in a bowl moved into another, empty bowl."""
    bowls = [b.obj_id for b in state.of_kind("bowl")]
    if len(bowls) < 2:
        return
    full = {b for b in bowls for i in movable if P.in_bowl(state, i, b)}
    empty = [b for b in bowls if b not in full]
    inside = _candidates(state, goal_ids, movable, rng, lambda i: any(P.in_bowl(state, i, b) for b in bowls))
    for i in inside:
        for b in (empty[int(k)] for k in rng.permutation(len(empty))):
            centre = state.pos(b)
            z = centre[2] - BOWL_HEIGHT / 2 + BOWL_FLOOR + state.spec(i).height / 2 + 0.001
            layout = _base(state, movable)
            layout[i] = Pose.of((centre[0], centre[1], z), state.poses[i].quat)
            yield Proposal(layout, (i,), f"{_label(state.spec(i))} put into the {_label(state.spec(b))}")


# ------------------------------------------------------------------------------------ hard cases
def shifted(state: SceneState, obj_id: int, offset: np.ndarray) -> SceneState:
    """The state with one object moved by ``offset`` in xy (no physics: for finding tolerances)."""
    p = state.poses[obj_id]
    poses = dict(state.poses)
    poses[obj_id] = Pose.of((p.pos[0] + offset[0], p.pos[1] + offset[1], p.pos[2]), p.quat)
    return SceneState(state.objects, poses, state.time, state.held)


def threshold(passes: Callable[[float], bool], hi: float = MAX_SHIFT, iters: int = 24) -> float | None:
    """The shift where ``passes`` turns false (bisection), None when it passes at ``hi`` or fails at 0."""
    if not passes(0.0) or passes(hi):
        return None
    lo = 0.0
    for _ in range(iters):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if passes(mid) else (lo, mid)
    return lo


def _passes_when_shifted(success: Callable[[SceneState], bool], state: SceneState, obj_id: int,
                         direction: np.ndarray) -> Callable[[float], bool]:
    return lambda d: success(shifted(state, obj_id, d * direction))


def near_tolerance(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int], rng: np.random.Generator,
                   success: Callable[[SceneState], bool], inside: bool, margin: float
                   ) -> Iterator[Proposal]:
    """One goal object shifted in a random horizontal direction to just inside (``inside``: half
    the distance at which the predicate flips) or just outside (``margin`` m beyond it)."""
    for i in _candidates(state, goal_ids, movable, rng, lambda i: True):
        for _ in range(3):
            angle = rng.uniform(-math.pi, math.pi)
            direction = np.array([math.cos(angle), math.sin(angle)])
            edge = threshold(_passes_when_shifted(success, state, i, direction))
            if edge is None or edge < 2 * margin:
                continue
            d = edge / 2 if inside else edge + margin
            p = state.poses[i]
            layout = _base(state, movable)
            layout[i] = Pose.of((p.pos[0] + d * direction[0], p.pos[1] + d * direction[1], p.pos[2] + 0.0005), p.quat)
            where = "inside" if inside else "outside"
            yield Proposal(layout, (i,), f"{_label(state.spec(i))} shifted {d * 1000:.1f} mm towards "
                                         f"{math.degrees(angle):.0f} deg, just {where} the tolerance "
                                         f"(the predicate flips at {edge * 1000:.1f} mm)")
