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
are still classified, from the error text alone.
"""

from __future__ import annotations

import re
from collections import Counter
from typing import Any, Iterable, Mapping

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


def _predicate(attempt: Mapping[str, Any]) -> bool | None:
    """The task predicate recorded for an attempt (field names of this and the reporter branch)."""
    for key in ("predicate", "predicate_success"):
        v = attempt.get(key)
        if isinstance(v, bool):
            return v
        if isinstance(v, Mapping) and isinstance(v.get("success"), bool):
            return v["success"]
    return None


def _error_label(error: str, attempt: Mapping[str, Any] | None) -> str:
    a = attempt or {}
    program = a.get("failed_program")
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
    if a.get("api_error"):
        return "api_misuse"
    if "api_error" not in a and "failed_program" not in a and _ARGUMENTS.search(error):
        return "api_misuse"  # an old record without the facts: ValueError/TypeError are argument errors
    return "plan_exception"


def classify(rec: Mapping[str, Any]) -> str | None:
    """The failure label of one episode record, None when it succeeded."""
    if rec.get("success") is True:
        return None
    error = rec.get("error") or None
    llm = rec.get("llm") or {}
    attempts = [a for a in (llm.get("attempts") or []) if isinstance(a, Mapping)]
    if error and (not rec.get("attempts") or _INFRA.search(str(error))):
        return "infrastructure"
    if llm.get("stopped") == "llm budget":
        return "budget"
    for a in attempts[:-1]:
        if a.get("verdict") is False and _predicate(a) is True:
            return "reporter_false_negative"
    last = attempts[-1] if attempts else None
    same = last.get("identical_to") if last is not None and last.get("not_run") else None
    if isinstance(same, int) and 1 <= same < len(attempts):
        last = attempts[same - 1]  # a plan not re-run ends the episode as that attempt's plan did
    if last is not None and last.get("error_kind") == "llm" or (error and str(error).startswith("LLMError")):
        return "llm_error"
    last_error = (last or {}).get("error") or error
    if last_error:
        return _error_label(str(last_error), last)
    if last is not None and last.get("verdict") is True and len(attempts) < int(llm.get("max_attempts") or 1):
        return "reporter_false_positive"
    drift = rec.get("drift") or {}
    if isinstance(drift.get("max_m"), (int, float)) and drift["max_m"] > DRIFT_TOL_M:
        return "physics"
    return "wrong_plan"


def failure_of(rec: Mapping[str, Any]) -> str | None:
    """The recorded label, or the classification of a record written before labels existed."""
    if "failure" in rec:
        return rec["failure"]
    return classify(rec)


def breakdown(records: Iterable[Mapping[str, Any]]) -> dict[str, int]:
    """Failure counts by label (labels in :data:`LABELS` order, only those that occur)."""
    counts = Counter(f for f in (failure_of(r) for r in records) if f is not None)
    order = {lab: i for i, lab in enumerate(LABELS)}
    return {lab: counts[lab] for lab in sorted(counts, key=lambda x: (order.get(x, len(order)), x))}
