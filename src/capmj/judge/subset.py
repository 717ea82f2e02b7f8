"""A deterministic, stratified subset of a judge set (``judge --per-task N``).

Why: a slow local model answers one state in tens of seconds, so the whole set (20 tasks × 5 seeds,
~700 states) takes hours; ~60-100 states give a usable first comparison of two prompts.  The
subset must still be balanced and the same for every model, so it is chosen from the cases alone:

* per task, the cases fall into four strata, taken in turn — ``oracle`` (achieved), the
  perturbation negatives (not), ``near_inside`` (achieved), ``near_outside`` (not) — so N = 4 gives
  two achieved and two failed states, one of each hard side;
* within a stratum the order is the SHA-256 of the case's key (``task/seed/case``): spread over
  seeds, independent of the model and of the other tasks; the negatives stratum alternates its
  kinds (``displaced``, ``unstacked``, ...) in that order, so N = 8 shows two different ones;
* a stratum that runs out is skipped; the cases keep the set's order.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence

from capmj.judge.cases import NEGATIVE_KINDS, JudgeCase

__all__ = ["STRATA", "stratified"]

STRATA: tuple[tuple[str, ...], ...] = (("oracle",), NEGATIVE_KINDS, ("near_inside",), ("near_outside",))
"""The strata of :func:`stratified`, in the order they are drawn from."""


def _rank(case: JudgeCase) -> str:
    return hashlib.sha256(case.key.encode()).hexdigest()


def _interleave(cases: Sequence[JudgeCase]) -> list[JudgeCase]:
    """``cases`` ordered by rank within each kind, the kinds taken in turn (by their order in the set)."""
    by_kind: dict[str, list[JudgeCase]] = {}
    for c in cases:
        by_kind.setdefault(c.kind, []).append(c)
    queues = [sorted(v, key=_rank) for v in by_kind.values()]
    out: list[JudgeCase] = []
    while any(queues):
        for q in queues:
            if q:
                out.append(q.pop(0))
    return out


def stratified(cases: Sequence[JudgeCase], per_task: int) -> list[JudgeCase]:
    """Up to ``per_task`` cases of each task (see the module docstring), in the set's order; cases of
    other kinds (``run``) are not drawn."""
    if per_task < 1:
        raise ValueError(f"--per-task must be >= 1, got {per_task}")
    chosen: set[str] = set()
    tasks = list(dict.fromkeys(c.task for c in cases))
    for task in tasks:
        mine = [c for c in cases if c.task == task]
        queues = [_interleave([c for c in mine if c.kind in stratum]) for stratum in STRATA]
        taken = 0
        while taken < per_task and any(queues):
            for q in queues:
                if q and taken < per_task:
                    chosen.add(q.pop(0).key)
                    taken += 1
    return [c for c in cases if c.key in chosen]
