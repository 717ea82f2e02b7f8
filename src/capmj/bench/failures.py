"""Failure attribution: why did a failed episode fail?  One label per failed episode.

:func:`classify` reads one ``episodes.jsonl`` record (nothing else) and returns a label from
:data:`LABELS`, or None for a successful episode.  The rules, in the order they are tried, are
documented with examples in ``docs/failures.md``; in short:

1. ``infrastructure`` — the episode never ran its agent or could not be judged (worker crash,
   scene generation or evaluation failed).
2. ``budget`` — the episode's LLM token/cost budget stopped it (``llm.stopped == "llm budget"``).
3. ``reporter_false_negative`` — an earlier attempt reached the goal (task predicate true on the
   state the reporter judged) but the reporter said "not achieved", so the scene was reset.
4. ``llm_error`` — the provider failed after the client's retries (attempt ``error_kind`` llm).
5. The last attempt raised: ``helper_lmp`` when the failed program is a helper LMP (its own code
   failed, whatever the kind), else by the error: ``no_code``, ``syntax``, ``sandbox_violation``,
   ``budget`` (wall time, lines, elements, API calls, primitives, simulation steps),
   ``unknown_object``, ``motion`` (unreachable / no grip / wrong object picked), ``api_misuse``
   (an API function rejected its arguments), ``plan_exception`` (the plan's own code raised).
   A last attempt whose plan was not run (identical to attempt j's, see docs/llm.md) is classified
   as attempt j, where its episode ended.
6. The last attempt ran cleanly but the predicate is false:
   ``reporter_false_positive`` when the reporter's "achieved" ended the loop with attempts left,
   ``physics`` when an object the last attempt placed ended more than :data:`DRIFT_TOL_M` from
   where its pick-and-place put it (a tower fell, a block slid off), else ``wrong_plan``.

Records written before these facts were recorded (no ``failed_program``/``api_error``/``drift``)
are still classified, from the error text alone.  :func:`classify` reads record attributes
(:class:`~capmj.records.Episode`); older lines are migrated to records by :mod:`capmj.bench.migrate`.
"""

from __future__ import annotations

import re
from collections import Counter
from typing import Iterable

from capmj.records import AttemptRecord, Episode, EpisodeRecord

__all__ = ["DRIFT_TOL_M", "LABELS", "breakdown", "classify", "failure_of"]

LABELS: tuple[str, ...] = (
    "no_code", "syntax", "sandbox_violation", "budget", "unknown_object", "api_misuse", "plan_exception",
    "helper_lmp", "motion", "physics", "wrong_plan", "reporter_false_positive", "reporter_false_negative",
    "llm_error", "infrastructure",
)
"""Every label :func:`classify` can return, in the order tables show them."""

DRIFT_TOL_M = 0.02
"""An object that ends farther than this from where its last pick-and-place put it has moved on
its own (the oracle's placements end within 2 mm)."""

_MOTION = re.compile(r"put_first_on_second\(.*failed: (unreachable|no_grip|timeout|held_nothing)"
                     r"|put_first_on_second: picked .* instead of")
_UNKNOWN = re.compile(r"unknown object|no object with obj_id")
_ARGUMENTS = re.compile(r"\b(ValueError|TypeError)\b")
_INFRA = re.compile(r"^(WorkerCrash|WorkerError)|^evaluation failed")


def _error_label(error: str, attempt: AttemptRecord | None) -> str:
    program = attempt.failed_program if attempt is not None else None
    if program and program != "planner":
        return "helper_lmp"
    if "no code in completion" in error:
        return "no_code"
    if "SyntaxError" in error:
        return "syntax"
    if "SandboxViolation" in error:
        return "sandbox_violation"
    if "BudgetExceeded" in error or "budget" in error.split(":", 1)[0].lower():
        return "budget"
    if _MOTION.search(error):
        return "motion"
    if _UNKNOWN.search(error):
        return "unknown_object"
    if attempt is not None and attempt.api_error is not None:
        return "api_misuse"
    if (attempt is None or attempt.failed_program is None) and _ARGUMENTS.search(error):
        return "api_misuse"  # a record without the facts: ValueError/TypeError are argument errors
    return "plan_exception"


def classify(rec: Episode) -> str | None:
    """The failure label of one episode, None when it succeeded."""
    if rec.success:
        return None
    error = rec.error or None
    llm = rec.llm
    attempts = rec.llm_attempts
    if error and (not rec.attempts or _INFRA.search(error)):
        return "infrastructure"
    if llm is not None and llm.stopped == "llm budget":
        return "budget"
    for a in attempts[:-1]:
        if a.verdict is False and a.predicate is True:
            return "reporter_false_negative"
    last = attempts[-1] if attempts else None
    same = last.identical_to if last is not None and last.not_run else None
    if same is not None and 1 <= same < len(attempts):
        last = attempts[same - 1]  # a plan not re-run ends the episode as that attempt's plan did
    if last is not None and last.error_kind == "llm" or (error and error.startswith("LLMError")):
        return "llm_error"
    last_error = (last.error if last is not None else None) or error
    if last_error:
        return _error_label(last_error, last)
    if last is not None and last.verdict is True and llm is not None and len(attempts) < (llm.max_attempts or 1):
        return "reporter_false_positive"
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
