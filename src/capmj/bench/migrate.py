"""The one place where ``episodes.jsonl`` lines of earlier capmj versions become today's records.

Every reader of a run folder gets :class:`~capmj.records.EpisodeRecord` objects from
:func:`load_record`; nothing else knows that older lines exist.  A line carrying today's
``schema`` is read strictly.  A line without ``schema`` was written before records were typed: it
is migrated here, then read with the record types' defaults for keys it lacks —

* keys it lacks take the defaults the readers used to assume (no ``attempts``: 0, no ``llm``: none);
* attempts written before re-plan retries carry ``extra_request`` (a flag: one request at most);
  the reporter branch's ``predicate_success`` and ``{"success": ...}`` predicates become
  ``predicate``;
* a line without a ``failure`` label (written before labels existed) is classified now.

A line with a ``schema`` this version does not know was written by a newer capmj and is refused.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from capmj.bench.failures import classify
from capmj.errors import RecordError
from capmj.records import SCHEMA, Episode, EpisodeRecord

__all__ = ["as_record", "load_record"]

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
    d: dict[str, Any] = {**_REQUIRED_DEFAULTS, **data}
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
