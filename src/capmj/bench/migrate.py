"""The one place where ``episodes.jsonl`` lines of earlier capmj versions become today's records.

Every reader of a run folder gets :class:`~capmj.records.EpisodeRecord` objects from
:func:`load_record`; nothing else knows that older lines exist.  A line carrying today's
``schema`` is read strictly.  A line without ``schema`` was written before records were typed: it
is migrated here, then read with the record types' defaults for keys it lacks —

* keys it lacks take the defaults the readers used to assume (no ``attempts``: 0, no ``llm``: none);
* attempts written before re-plan retries carry ``extra_request`` (a flag: one request at most);
  the reporter branch's ``predicate_success`` and ``{"success": ...}`` predicates become
  ``predicate``;
* lines of ``capmj.episode/1`` and older hold no ``error_type``/``error_status``: they are read
  from the error text by :func:`legacy_error_type` — the only place where capmj still parses an
  error message, kept for these old lines alone;
* a line without a ``failure`` label (written before labels existed) is classified now;
* ``capmj.episode/2`` lines are today's without ``perception`` (every episode then read the
  simulator): they are read as they are, with no perception record.

A line with a ``schema`` this version does not know was written by a newer capmj and is refused.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

from capmj.bench.failures import classify
from capmj.errors import (
    BudgetExceeded,
    EvaluationFailed,
    LLMBudgetExceeded,
    LLMError,
    MotionFailed,
    NoCodeError,
    PlanSyntaxError,
    RecordError,
    SandboxViolation,
    UnknownObjectError,
)
from capmj.records import SCHEMA, Episode, EpisodeRecord

__all__ = ["as_record", "legacy_error_type", "load_record"]

SCHEMA_V1 = "capmj.episode/1"
"""Typed records before ``error_type``/``error_status`` (otherwise today's keys)."""
SCHEMA_V2 = "capmj.episode/2"
"""Typed records before ``perception`` (otherwise today's keys)."""

_REQUIRED_DEFAULTS: dict[str, Any] = {"model": None, "success": False, "progress": 0.0, "reward": 0.0,
                                      "primitives": 0, "attempts": 0, "sim_s": 0.0, "wall_s": 0.0, "error": None}
"""What a legacy line without these keys meant to the readers of its time (``.get`` defaults)."""


def load_record(data: Mapping[str, Any]) -> EpisodeRecord:
    """The record of one parsed ``episodes.jsonl`` line, of today's schema or an older one."""
    if not isinstance(data, Mapping):
        raise RecordError(f"EpisodeRecord: expected an object, got {type(data).__name__}")
    schema = data.get("schema")
    if schema == SCHEMA:
        return EpisodeRecord.from_dict(data)
    if schema == SCHEMA_V2:
        return EpisodeRecord.from_dict({**data, "schema": SCHEMA})
    if schema == SCHEMA_V1:
        return EpisodeRecord.from_dict(_with_error_types({**data, "schema": SCHEMA}))
    if schema is not None:
        raise RecordError(f"episode record of schema {schema!r}: written by a newer capmj (this one reads {SCHEMA!r})")
    return _legacy(data)


def as_record(rec: Episode | Mapping[str, Any]) -> EpisodeRecord:
    """``rec`` as a record: a record as it is, a runner result labelled, a parsed line loaded."""
    if isinstance(rec, EpisodeRecord):
        return rec
    if isinstance(rec, Episode):
        return EpisodeRecord.of(rec, failure=classify(rec))
    return load_record(rec)


def _legacy(data: Mapping[str, Any]) -> EpisodeRecord:
    d: dict[str, Any] = _with_error_types({**_REQUIRED_DEFAULTS, **data})
    llm = d.get("llm")
    if isinstance(llm, Mapping) and llm:
        d["llm"] = {"model": d.get("model") or "", **llm,
                    "attempts": [_legacy_attempt(a) for a in llm.get("attempts") or [] if isinstance(a, Mapping)]}
    labelled = "failure" in d
    record = EpisodeRecord.from_dict({**d, "schema": SCHEMA}, strict=False)
    return record if labelled else EpisodeRecord.of(record, failure=classify(record), transcript=record.transcript)


def _legacy_attempt(a: Mapping[str, Any]) -> dict[str, Any]:
    out = dict(a)
    if "extra_requests" not in out:
        out["extra_requests"] = int(bool(out.pop("extra_request", False)))
    out.pop("extra_request", None)
    out["predicate"] = None
    for key in ("predicate", "predicate_success"):  # the first that holds a verdict, as classify read them
        v = a.get(key)
        v = v.get("success") if isinstance(v, Mapping) else v
        if isinstance(v, bool):
            out["predicate"] = v
            break
    out.pop("predicate_success", None)
    return out


def _with_error_types(d: dict[str, Any]) -> dict[str, Any]:
    """``d`` with ``error_type``/``error_status`` on the episode and on every attempt with an error."""
    d["error_type"], d["error_status"] = legacy_error_type(d.get("error"))
    llm = d.get("llm")
    if isinstance(llm, Mapping) and isinstance(llm.get("attempts"), list):
        attempts = []
        for a in llm["attempts"]:
            if isinstance(a, Mapping) and a.get("error"):
                error_type, status = legacy_error_type(a["error"])
                a = {**a, "error_type": error_type, "error_status": status}
            attempts.append(a)
        d["llm"] = {**llm, "attempts": attempts}
    return d


# ---------------------------------------------------------------- legacy migration: error text -> class
_MOTION = re.compile(r"put_first_on_second\(.*failed: (unreachable|no_grip|timeout|held_nothing)"
                     r"|put_first_on_second: picked .* instead of")
_UNKNOWN = re.compile(r"unknown object|no object with obj_id")
_ARGUMENTS = re.compile(r"\b(ValueError|TypeError)\b")
_INFRA = re.compile(r"^(WorkerCrash|WorkerError)\b")


def legacy_error_type(error: str | None) -> tuple[str | None, str | None]:
    """``(error_type, status)`` of an error recorded before its class was: the rules failure
    attribution applied to the message then, in their order, so an old line keeps its label.
    Only for lines of ``capmj.episode/1`` and older; new lines record the class itself."""
    if not error:
        return None, None
    head = error.split(":", 1)[0]
    infra = _INFRA.match(error)
    if infra:
        return infra[1], None
    if error.startswith("evaluation failed"):
        return EvaluationFailed.__name__, None
    if error.startswith("LLMError"):
        return LLMError.__name__, None
    if "no code in completion" in error:
        return NoCodeError.__name__, None
    if "SyntaxError" in error:
        return PlanSyntaxError.__name__, None
    if "SandboxViolation" in error:
        return SandboxViolation.__name__, None
    if "BudgetExceeded" in error or "budget" in head.lower():
        return (LLMBudgetExceeded if head == LLMBudgetExceeded.__name__ else BudgetExceeded).__name__, None
    motion = _MOTION.search(error)
    if motion:
        return MotionFailed.__name__, motion[1] or "wrong_object"
    if _UNKNOWN.search(error):
        return UnknownObjectError.__name__, None
    arguments = _ARGUMENTS.search(error)
    if arguments:
        return arguments[1], None
    return (head if head.isidentifier() else None), None
