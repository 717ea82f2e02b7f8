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

__all__ = ["MAX_SHIFT", "Proposal", "displaced", "free_spot", "near_tolerance", "shifted_all", "swapped", "threshold",
           "tower_of", "toppled", "toppled_out", "unstacked", "wrong_bowl"]

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
CLEAR_STEP = 0.005
"""Step (m) of the search for where a shifted object rests clear of the others (``near_outside`` in bowls)."""
CLEAR_EXTRA = 0.05
"""How far beyond ``MAX_SHIFT`` (m) that search goes."""


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
              ignore: Sequence[int] = (), keep: Callable[[np.ndarray], bool] | None = None) -> np.ndarray | None:
    """A random xy on the table where ``obj_id``'s footprint keeps ``GAP`` from every other object
    (zones included: a block dropped in another zone would test that zone, not the displacement),
    optionally within ``radius`` of ``near``, ignoring the objects ``ignore`` (those that move
    too) and where ``keep(xy)`` holds; None when ``SPOT_TRIES`` draws find none."""
    spec = state.spec(obj_id)
    b = centre_bounds(spec.footprint_radius, SPAWN_BOUNDS)
    others = [(state.pos(o.obj_id)[:2], o.footprint_radius) for o in state.objects
              if o.obj_id != obj_id and o.obj_id not in ignore]
    others += [(np.asarray(c, float)[:2], float(r)) for c, r in avoid]
    for _ in range(SPOT_TRIES):
        xy = np.array([rng.uniform(b.xmin, b.xmax), rng.uniform(b.ymin, b.ymax)])
        if near is not None and math.hypot(*(xy - near[:2])) > radius:
            continue
        if keep is not None and not keep(xy):
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


def tower_of(state: SceneState, ids: Sequence[int], top: int) -> list[int]:
    """The objects of ``ids`` within ``TOWER_RADIUS`` of ``top`` in xy (its tower, base included)."""
    return sorted(i for i in ids if math.hypot(*(state.pos(i)[:2] - state.pos(top)[:2])) <= TOWER_RADIUS)


def _same_place(state: SceneState, obj_id: int) -> Callable[[np.ndarray], bool]:
    """Whether an xy keeps what ``obj_id``'s position means: the same zones (the tasks' centre-in-square
    rule) and the same quarter of the table."""
    zones = [z.obj_id for z in state.of_kind("zone") if P.in_zone(state, obj_id, z.obj_id)]
    here = state.pos(obj_id)
    quarter = [q for q in P.QUADRANTS if P.in_area(here, q)]

    def keep(xy: np.ndarray) -> bool:
        point = np.array([xy[0], xy[1], here[2]])
        return all(P.in_square(point, state.pos(z), state.poses[z].yaw, P.zone_half_size(state.spec(z)))
                   for z in zones) and all(P.in_area(point, q) for q in quarter)

    return keep


def toppled(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int],
            rng: np.random.Generator) -> Iterator[Proposal]:
    """A tower knocked over where it stood: the goal objects of the highest stack or structure
    (:func:`tower_of` the highest one, its base included) lie on the table around where it stood
    (random spots within ``TOPPLE_RADIUS``, random yaw), each still in the zones and the quarter of
    the table its base was in.

    Why the last condition: a tower that falls out of its zone breaks two success conditions at
    once (stacked, in the zone), and a reporter that says "not achieved" would be right for either
    reason; kept in place, the case tests the stack alone.  A tower whose blocks do not fit lying
    there yields nothing; :func:`toppled_out` covers it."""
    yield from _topple(state, goal_ids, movable, rng, in_place=True)


def toppled_out(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int],
                rng: np.random.Generator) -> Iterator[Proposal]:
    """Only where :func:`toppled` finds no room: the tower knocked over around where it stood and
    out of its zone and quarter (the free spots avoid every zone), breaking the stack *and* the
    placement — its own kind, so that its label says both."""
    if next(_topple(state, goal_ids, movable, np.random.default_rng(0), in_place=True), None) is not None:
        return
    yield from _topple(state, goal_ids, movable, rng, in_place=False)


def _topple(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int], rng: np.random.Generator,
            in_place: bool) -> Iterator[Proposal]:
    bowls = [b.obj_id for b in state.of_kind("bowl")]
    ids = [i for i in goal_ids if i in movable and not any(P.in_bowl(state, i, b) for b in bowls)]
    up = [i for i in ids if elevated(state, i)]
    if not up:
        return
    top = max(up, key=lambda i: (float(state.pos(i)[2]), i))
    tower = tower_of(state, ids, top)
    base = min(tower, key=lambda i: (float(state.pos(i)[2]), i))
    keep = _same_place(state, base) if in_place else None
    zones = [z.obj_id for z in state.of_kind("zone") if P.in_zone(state, base, z.obj_id)] if in_place else []
    for _ in range(3):
        layout = _base(state, movable)
        placed: list[tuple[np.ndarray, float]] = []
        for i in tower:
            xy = free_spot(state, i, rng, near=state.pos(top), radius=TOPPLE_RADIUS + TOPPLE_PER_BLOCK * len(tower),
                           avoid=placed, ignore=[*tower, *zones], keep=keep)
            if xy is None:
                break
            placed.append((xy, state.spec(i).footprint_radius))
            layout[i] = _on_table(state.spec(i), xy, rng.uniform(-math.pi / 4, math.pi / 4))
        else:
            names = ", ".join(_label(state.spec(i)) for i in tower)
            if not in_place:
                where = " around it, out of where it stood (the stack and the placement broken)"
            else:
                where = (f" in the {_label(state.spec(zones[0]))}" if zones else "") + " where it stood"
            yield Proposal(layout, tuple(tower), f"tower knocked over: {names} lie on the table{where}")


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


def shifted_all(state: SceneState, ids: Sequence[int], offset: np.ndarray) -> SceneState:
    """The state with the objects ``ids`` moved together by ``offset`` in xy (no physics)."""
    for i in ids:
        state = shifted(state, i, offset)
    return state


def _passes_when_all_shifted(success: Callable[[SceneState], bool], state: SceneState, ids: Sequence[int],
                             direction: np.ndarray) -> Callable[[float], bool]:
    return lambda d: success(shifted_all(state, ids, d * direction))


def _clear_distance(state: SceneState, obj_id: int, direction: np.ndarray, start: float) -> float | None:
    """The smallest shift >= ``start`` along ``direction`` (in ``CLEAR_STEP`` steps, up to
    ``MAX_SHIFT`` + ``CLEAR_EXTRA``) at which ``obj_id``'s footprint keeps ``GAP`` from every other
    object's; None when there is none."""
    p, r = state.pos(obj_id)[:2], state.spec(obj_id).footprint_radius
    others = [(state.pos(o.obj_id)[:2], o.footprint_radius) for o in state.objects
              if o.obj_id != obj_id and o.kind != "zone"]
    d = start
    while d <= MAX_SHIFT + CLEAR_EXTRA:
        xy = p + d * direction
        if all(math.hypot(*(xy - c)) >= rc + r + GAP for c, rc in others):
            return d
        d += CLEAR_STEP
    return None


def near_tolerance(state: SceneState, goal_ids: Sequence[int], movable: Sequence[int], rng: np.random.Generator,
                   success: Callable[[SceneState], bool], inside: bool, margin: float
                   ) -> Iterator[Proposal]:
    """One goal object shifted in a random horizontal direction to just inside (``inside``: half
    the distance at which the predicate flips) or just outside (``margin`` m beyond it).

    Where physics cannot hold an object there (the set builder rejects a proposal whose object did
    not stay where it was put), two fall-backs follow, in this order:

    * outside only, an object in a bowl: along each direction tried, the nearest distance beyond the
      edge at which it rests on the table clear of the bowl and the other objects
      (:func:`_clear_distance`), the nearest to its tolerance first — inside, the wall pushes a
      block shifted past the 5 cm tolerance back in;
    * a tower (a goal object on top of others, :func:`tower_of`) shifted as a whole, to just inside
      or outside the distance at which the predicate flips (e.g. its base leaves the zone) — a 2 cm
      block shifted past a stack's 2 cm axis tolerance falls off, a whole tower stands.

    They come after every single-object proposal, so a (task, seed) that had a single-object case
    keeps it."""
    tried: list[tuple[int, float, np.ndarray, float]] = []
    for i in _candidates(state, goal_ids, movable, rng, lambda i: True):
        for _ in range(3):
            angle = rng.uniform(-math.pi, math.pi)
            direction = np.array([math.cos(angle), math.sin(angle)])
            edge = threshold(_passes_when_shifted(success, state, i, direction))
            if edge is None or edge < 2 * margin:
                continue
            tried.append((i, angle, direction, edge))
            yield _shift((i,), state, movable, angle, edge / 2 if inside else edge + margin, edge, inside)
    bowls = [b.obj_id for b in state.of_kind("bowl")]
    clear = []
    for n, (i, angle, direction, edge) in enumerate(tried if not inside else ()):
        d = _clear_distance(state, i, direction, edge + margin) if any(P.in_bowl(state, i, b) for b in bowls) else None
        if d is not None:
            clear.append((d - edge, n, i, angle, d, edge))
    for _, _, i, angle, d, edge in sorted(clear):  # the nearest to its tolerance first
        yield _shift((i,), state, movable, angle, d, edge, inside, on_table=True)
    for top in _candidates(state, goal_ids, movable, rng, lambda i: elevated(state, i)):
        tower = tower_of(state, [i for i in movable if state.pos(i)[2] <= state.pos(top)[2] + 1e-6], top)
        if len(tower) < 2:
            continue
        for _ in range(3):
            angle = rng.uniform(-math.pi, math.pi)
            direction = np.array([math.cos(angle), math.sin(angle)])
            edge = threshold(_passes_when_all_shifted(success, state, tower, direction))
            if edge is None or edge < 2 * margin:
                continue
            yield _shift(tuple(tower), state, movable, angle, edge / 2 if inside else edge + margin, edge, inside)


def _shift(ids: tuple[int, ...], state: SceneState, movable: Sequence[int], angle: float, d: float, edge: float,
           inside: bool, on_table: bool = False) -> Proposal:
    """The proposal that moves ``ids`` together by ``d`` towards ``angle`` (``on_table``: resting on
    the table there, else 0.5 mm above where they were)."""
    direction = np.array([math.cos(angle), math.sin(angle)])
    layout = _base(state, movable)
    for i in ids:
        p = state.poses[i]
        xy = np.asarray(p.pos[:2]) + d * direction
        layout[i] = _on_table(state.spec(i), xy, p.yaw) if on_table else Pose.of(
            (float(xy[0]), float(xy[1]), p.pos[2] + 0.0005), p.quat)
    what = _label(state.spec(ids[0])) if len(ids) == 1 else "tower of " + ", ".join(_label(state.spec(i)) for i in ids)
    where = "inside" if inside else "outside"
    rest = ", on the table clear of the bowl" if on_table else ""
    return Proposal(layout, ids, f"{what} shifted {d * 1000:.1f} mm towards {math.degrees(angle):.0f} deg, just "
                                 f"{where} the tolerance{rest} (the predicate flips at {edge * 1000:.1f} mm)")
