"""Failure attribution: why did a failed episode fail?  One label per failed episode.

:func:`classify` reads one ``episodes.jsonl`` record (nothing else) and returns a label from
:data:`LABELS`, or None for a successful episode.  The rules, in the order they are tried, are
documented with examples in ``docs/failures.md``; in short:

1. ``infrastructure`` — the episode never ran its agent or could not be judged (worker crash,
   scene generation or evaluation failed); also, tried after rule 3, an LLM episode whose error is
   not a capmj error class and not its last attempt's error: the agent's loop crashed, not the plan.
2. ``budget`` — the episode's LLM token/cost budget stopped it (``llm.stopped == "llm budget"``);
   ``no_finish`` — a multi-turn episode used its ``--max-turns`` without the model saying FINISH
   (``llm.stopped == "turns used up"``), whatever its last turn did.
3. ``reporter_false_negative`` — an earlier attempt reached the goal (task predicate true on the
   state the reporter judged) but the reporter said "not achieved", so the scene was reset.
4. ``llm_error`` — the provider failed after the client's retries (attempt ``error_kind`` llm).
5. The last attempt raised: ``helper_lmp`` when the failed program is a helper LMP (its own code
   failed, whatever the kind), else by the class of the error (``error_type``, recorded per
   attempt and per episode by :func:`capmj.errors.error_facts`; never by its message): ``no_code``, ``syntax``, ``sandbox_violation``,
   ``budget`` (wall time, lines, elements, API calls, primitives, simulation steps),
   ``unknown_object``, ``perception`` (a pick missed because the perceived point lay off the
   object, ``PerceptionFailed``; rgbd mode), ``collision`` (a move of the low-level API touched what it
   was not meant to, ``CollisionDetected``), ``motion`` (unreachable / no path / IK failure / no grip /
   wrong object picked), ``api_misuse``
   (an API function rejected its arguments), ``plan_exception`` (the plan's own code raised).
   A last attempt whose plan was not run (identical to attempt j's, see docs/llm.md) is classified
   as attempt j, where its episode ended.
6. The last attempt ran cleanly but the predicate is false:
   ``reporter_false_positive`` when the reporter's "achieved" ended the loop with attempts left,
   ``perception`` when the episode read the cameras and the last attempt acted on a view that got
   an object wrong or picked off target (:meth:`capmj.records.PerceptionNotes.erred`: a missed or
   false object, a wrong kind / colour / size, a centre more than 10 mm off, a fixture slot
   more than 3 mm off),
   ``physics`` when an object the last attempt placed ended more than :data:`DRIFT_TOL_M` from
   where its pick-and-place put it (a tower fell, a block slid off), else ``wrong_plan``.

:func:`classify` reads record attributes (:class:`~capmj.records.Episode`).  Lines written before
``error_type`` was recorded get one from their error text when they are loaded, in the one place
that reads old lines (:mod:`capmj.bench.migrate`); lines without ``failed_program``/``api_error``
(non-LLM agents, old runs) take a ValueError/TypeError as an argument error (``api_misuse``).
"""

from __future__ import annotations

from collections import Counter
from typing import Iterable

from capmj.errors import (
    BudgetExceeded,
    CapmjError,
    CollisionDetected,
    InfrastructureError,
    LLMError,
    MotionFailed,
    NoCodeError,
    PerceptionFailed,
    PlanSyntaxError,
    PortingDifference,
    SandboxViolation,
    UnknownObjectError,
    error_class,
)
from capmj.records import AttemptRecord, Episode, EpisodeRecord
from capmj.records.notes import TURNS_USED_UP

__all__ = ["DRIFT_TOL_M", "LABELS", "breakdown", "classify", "failure_of"]

LABELS: tuple[str, ...] = (
    "no_code", "syntax", "sandbox_violation", "budget", "unknown_object", "api_misuse", "plan_exception",
    "helper_lmp", "perception", "collision", "motion", "physics", "wrong_plan", "reporter_false_positive", "reporter_false_negative",
    "llm_error", "no_finish", "infrastructure",
)
"""Every label :func:`classify` can return, in the order tables show them."""

DRIFT_TOL_M = 0.02
"""An object that ends farther than this from where its last pick-and-place put it has moved on
its own (the oracle's placements end within 2 mm)."""

def _is(error_type: str | None, *kinds: type[BaseException]) -> bool:
    cls = error_class(error_type)
    return cls is not None and issubclass(cls, kinds)


def _error_label(error_type: str | None, attempt: AttemptRecord | None) -> str:
    """The label of an attempt (or a non-LLM episode) that raised, from the class of what failed."""
    program = attempt.failed_program if attempt is not None else None
    if program and program != "planner":
        return "helper_lmp"
    for kind, label in _KINDS:
        if _is(error_type, kind):
            return label
    if attempt is not None and attempt.api_error is not None:
        return "api_misuse"
    misuse = error_class(error_type) in (ValueError, TypeError) or _is(error_type, PortingDifference)
    if (attempt is None or attempt.failed_program is None) and misuse:
        return "api_misuse"  # no attempt facts (a plan of a non-LLM agent): an argument error of an API function
    return "plan_exception"


_KINDS: tuple[tuple[type[BaseException], str], ...] = (
    (NoCodeError, "no_code"), (PlanSyntaxError, "syntax"), (SandboxViolation, "sandbox_violation"),
    (BudgetExceeded, "budget"), (PerceptionFailed, "perception"), (CollisionDetected, "collision"),
    (MotionFailed, "motion"),
    (UnknownObjectError, "unknown_object"),
)
"""Error classes with a label of their own, tried in this order."""


def _attempt_number(rec: Episode, last: AttemptRecord | None) -> int:
    """The 1-based attempt the episode ended with (that of ``last`` for an LLM episode)."""
    return last.attempt if last is not None else max(rec.attempts, 1)


def classify(rec: Episode) -> str | None:
    """The failure label of one episode, None when it succeeded."""
    if rec.success:
        return None
    error = rec.error or None
    llm = rec.llm
    attempts = rec.llm_attempts
    if error and (not rec.attempts or _is(rec.error_type, InfrastructureError)):
        return "infrastructure"
    if llm is not None and llm.stopped == "llm budget":
        return "budget"
    if llm is not None and llm.stopped == TURNS_USED_UP:
        return "no_finish"
    for a in attempts[:-1]:
        if a.verdict is False and a.predicate is True:
            return "reporter_false_negative"
    last = attempts[-1] if attempts else None
    same = last.identical_to if last is not None and last.not_run else None
    if same is not None and 1 <= same < len(attempts):
        last = attempts[same - 1]  # a plan not re-run ends the episode as that attempt's plan did
    if error and llm is not None and rec.error_type and not _is(rec.error_type, CapmjError) and \
            (last is None or last.error != error):
        return "infrastructure"  # the LLM agent's loop raised what no plan raised: a crash inside capmj
    if last is not None and last.error_kind == "llm" or (error and _is(rec.error_type, LLMError)):
        return "llm_error"
    if last is not None and last.error:
        return _error_label(last.error_type, last)
    if error:
        return _error_label(rec.error_type, last)
    if last is not None and last.verdict is True and llm is not None and len(attempts) < (llm.max_attempts or 1):
        return "reporter_false_positive"
    if rec.perception is not None and rec.perception.erred(_attempt_number(rec, last)):
        return "perception"
    if rec.drift is not None and rec.drift.max_m is not None and rec.drift.max_m > DRIFT_TOL_M:
        return "physics"
    return "wrong_plan"


def failure_of(rec: EpisodeRecord) -> str | None:
    """The recorded label (records written before labels existed are labelled when loaded,
    :mod:`capmj.bench.migrate`)."""
    return rec.failure


def breakdown(records: Iterable[EpisodeRecord]) -> dict[str, int]:
    """Failure counts by label (labels in :data:`LABELS` order, only those that occur)."""
    counts = Counter(r.failure for r in records if r.failure is not None)
    order = {lab: i for i, lab in enumerate(LABELS)}
    return {lab: counts[lab] for lab in sorted(counts, key=lambda x: (order.get(x, len(order)), x))}
