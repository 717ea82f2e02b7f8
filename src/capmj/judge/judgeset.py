"""The labelled set of final states for tasks × seeds: positives, negatives and hard cases.

Per (task, seed): the oracle solves the episode through real pick-and-place; its final layout,
placed on the initial world and settled, is the positive (``oracle``).  Each perturbation kind of
:mod:`capmj.judge.perturb` then proposes layouts from that settled state, and the first proposal
that survives the checks below becomes that kind's case:

* realised and settled in MuJoCo (:meth:`capmj.judge.cases.Stage.realise`), the task predicate
  gives the intended label (negatives and ``near_outside`` fail, ``near_inside`` passes);
* every object the proposal did not move ends within ``STILL_TOL`` of where it stood, and for the
  hard cases the shifted object within ``PLACE_TOL`` of where it was put: the perturbation changed
  what it says and nothing else, and the state is what a real run could show.

A kind that has nothing to act on (no stack to topple, no bowl) or whose proposals all fail the
checks is recorded as skipped with the reason.  Randomness: one generator per (task, seed, kind)
from a ``SeedSequence``, so adding a kind never changes the others, and the same ``--tasks`` and
``--seeds`` always give the same set (same digest, in any process).
"""

from __future__ import annotations

import math
import sys
import zlib
from dataclasses import dataclass, replace
from typing import Any, Callable, Iterable, Iterator, Sequence

import numpy as np

from capmj.agents.oracle import OracleAgent
from capmj.judge import perturb
from capmj.judge.cases import HARD_KINDS, KINDS, JudgeCase, Stage, layout_of, layout_rows
from capmj.judge.perturb import Proposal
from capmj.sim.state import Pose, SceneState
from capmj.tasks import registry
from capmj.tasks.protocol import Task

__all__ = ["MAX_HARD_PROPOSALS", "MAX_PROPOSALS", "NEAR_MARGIN", "PLACE_TOL", "STILL_TOL", "JudgeSet", "Skip", "build_cases",
           "build_set", "kind_rng"]

STILL_TOL = 0.005
"""Objects a perturbation did not move must end within this distance (m, 3-D) of where they stood."""
PLACE_TOL = 0.003
"""A hard case's shifted object must rest within this xy distance (m) of where it was put."""
NEAR_MARGIN = 0.004
"""``near_outside`` puts the object this far (m) beyond the shift at which the predicate flips."""
MAX_PROPOSALS = 12
"""Proposals tried per kind before the kind is skipped for that (task, seed)."""
MAX_HARD_PROPOSALS = 24
"""The same for the hard kinds, whose fall-backs (a bowl's outside, a whole tower) come after up to
three proposals per goal object (:func:`capmj.judge.perturb.near_tolerance`)."""


@dataclass(frozen=True)
class Skip:
    """A case the set does not have, and why (``kind`` is ``oracle`` when the whole seed is out)."""

    task: str
    seed: int
    kind: str
    reason: str


@dataclass(frozen=True)
class JudgeSet:
    cases: tuple[JudgeCase, ...]
    skipped: tuple[Skip, ...]


def kind_rng(task: str, seed: int, kind: str) -> np.random.Generator:
    """The generator of one kind's proposals for (task, seed): from the names' CRC32s and the seed."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), zlib.crc32(task.encode()),
                                                         zlib.crc32(kind.encode())]))


_GENERATOR = {"near_inside": "near_tolerance", "near_outside": "near_tolerance"}
"""The perturbation function of a kind whose name differs from it."""


def _proposals(kind: str, base: SceneState, goal_ids: Sequence[int], movable: Sequence[int],
               rng: np.random.Generator, success: Callable[[SceneState], bool]) -> Iterator[Proposal]:
    if kind in HARD_KINDS:
        return perturb.near_tolerance(base, goal_ids, movable, rng, success, inside=kind == "near_inside",
                                      margin=NEAR_MARGIN)
    fn = {"displaced": perturb.displaced, "unstacked": perturb.unstacked, "toppled": perturb.toppled,
          "swapped": perturb.swapped, "wrong_bowl": perturb.wrong_bowl, "toppled_out": perturb.toppled_out}[kind]
    return fn(base, goal_ids, movable, rng)


def _problem(kind: str, prop: Proposal, state: SceneState, success: bool) -> str | None:
    """Why a realised proposal is not kept, else None."""
    want = kind == "near_inside"
    if success != want:
        return f"predicate {'passes' if success else 'fails'}"
    for i, pose in prop.layout.items():
        d = float(np.linalg.norm(state.pos(i) - np.asarray(pose.pos)))
        if i not in prop.moved and d > STILL_TOL:
            return f"object {i} was disturbed by {d:.3f} m"
        if i in prop.moved and kind in HARD_KINDS and math.hypot(*(state.pos(i)[:2] - pose.pos[:2])) > PLACE_TOL:
            return f"shifted object {i} did not stay where it was put"
    return None


def build_cases(task: Task, seed: int, kinds: Iterable[str] = KINDS) -> tuple[list[JudgeCase], list[Skip]]:
    """The cases of one (task, seed); ``kinds`` selects which (``oracle`` always comes first)."""
    name = str(task.name)
    stage = Stage(task, seed)
    world = stage.world
    movable = world.movable_ids
    try:
        OracleAgent().act(stage.context())
    except Exception as exc:  # noqa: BLE001 - an unsolvable seed is skipped, with the reason
        return [], [Skip(name, seed, "oracle", f"oracle failed: {type(exc).__name__}: {exc}")]
    # the oracle's layout settled once on the initial world: the positive, and what perturbations start from
    base = stage.realise(layout_of(world.state(), movable))
    solved = _stored(layout_of(base, movable))
    verdict = stage.evaluate(stage.realise(solved))
    if not verdict.success:
        return [], [Skip(name, seed, "oracle", "oracle state fails the predicate: " + "; ".join(verdict.diagnostics))]
    cases = [JudgeCase(name, seed, "oracle", "oracle", True, "", "the oracle's final state", verdict.progress,
                       layout_rows(solved))]
    skipped: list[Skip] = []
    goal_ids = sorted({i for g in task.oracle_goals(stage.scene) for i in g.objects})

    def success(state: SceneState) -> bool:
        return bool(stage.evaluate(state).success)

    for kind in kinds:
        if kind == "oracle":
            continue
        if kind not in KINDS:
            raise ValueError(f"unknown case kind {kind!r}; valid kinds: {', '.join(KINDS)}")
        reasons: list[str] = []
        gen = _proposals(kind, base, goal_ids, movable, kind_rng(name, seed, kind), success)
        for prop in _take(gen, MAX_HARD_PROPOSALS if kind in HARD_KINDS else MAX_PROPOSALS):
            prop = replace(prop, layout=_stored(prop.layout))
            state = stage.realise(prop.layout)
            v = stage.evaluate(state)
            problem = _problem(kind, prop, state, v.success)
            if problem is None:
                condition = "" if v.success else "; ".join(v.diagnostics)
                cases.append(JudgeCase(name, seed, kind, kind, bool(v.success), condition, prop.detail, v.progress,
                                       layout_rows(prop.layout)))
                break
            reasons.append(problem)
        else:
            why = (f"no proposal: nothing to perturb or no room (capmj.judge.perturb.{_GENERATOR.get(kind, kind)})"
                   if not reasons else f"{len(reasons)} proposal(s) rejected: {reasons[0]}")
            skipped.append(Skip(name, seed, kind, why))
    return cases, skipped


def _stored(layout: dict[int, Pose]) -> dict[int, Pose]:
    """The layout as a case stores it (rounded rows): labels are computed on exactly what is replayed."""
    return {int(r[0]): Pose.of(r[1:4], r[4:8]) for r in layout_rows(layout)}


def _take(it: Iterator[Proposal], n: int) -> Iterator[Proposal]:
    for k, item in enumerate(it):
        if k >= n:
            return
        yield item


def build_set(task_names: Sequence[str], seeds: Sequence[int], *, kinds: Iterable[str] = KINDS,
              progress: bool = False, get_task: Callable[[str], Any] | None = None) -> JudgeSet:
    """Cases for every (task, seed), tasks outer, in the given order (a progress bar when asked)."""
    lookup: Callable[[str], Any] = registry.get_task if get_task is None else get_task
    kinds = tuple(kinds)
    unknown = [k for k in kinds if k not in KINDS]
    if unknown:
        raise ValueError(f"unknown case kind(s) {', '.join(unknown)}; valid kinds: {', '.join(KINDS)}")
    pairs = [(t, s) for t in task_names for s in seeds]
    bar: Any = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(pairs), file=sys.stderr, unit="seed", dynamic_ncols=True, desc="judge set")
    cases: list[JudgeCase] = []
    skipped: list[Skip] = []
    try:
        for t, s in pairs:
            c, k = build_cases(lookup(t), s, kinds)
            cases += c
            skipped += k
            if bar is not None:
                bar.set_postfix_str(f"{len(cases)} cases", refresh=False)
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    return JudgeSet(tuple(cases), tuple(skipped))

