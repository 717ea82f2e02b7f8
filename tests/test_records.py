"""Typed, versioned episode records: strict reading, lossless round trips, and run folders written
before records were typed (tests/old_runs/cf25f28, written by main at that commit) still load and
summarise exactly as they did."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from capmj.bench.cli import main
from capmj.bench.migrate import load_record
from capmj.bench.report import summarize_dir
from capmj.bench.results import read_records
from capmj.bench.failures import classify
from capmj.errors import MotionFailed, PlanError, RecordError, SandboxViolation, describe, error_facts
from capmj.records import ATTEMPT_FIELDS, SCHEMA, AttemptRecord, EpisodeRecord, EpisodeResult
from capmj.replay.run_dir import failed_episodes

OLD = Path(__file__).parent / "old_runs" / "cf25f28"


def lines(folder: str) -> list[dict]:
    return [json.loads(x) for x in (OLD / folder / "episodes.jsonl").read_text().splitlines()]


ADDED = {"schema", "error_type", "error_status"}
LOOP_KEYS = {"loop_policy", "reporter_prompt", "rule", "confidence", "low_confidence"}
"""Keys added with issue #26's loop policies (capmj.records DEFAULT_IF_MISSING): written with their defaults."""


def kept(old: object, new: object, where: str = "") -> list[str]:
    """Where ``new`` lost or changed a key of ``old`` or added one outside ADDED ([] when none)."""
    if isinstance(old, dict) and isinstance(new, dict):
        out = [f"{where}.{k} lost" for k in old if k not in new]
        out += [f"{where}.{k} added" for k in new if k not in old and k not in ADDED | LOOP_KEYS]
        return out + [x for k in old if k in new for x in kept(old[k], new[k], f"{where}.{k}")]
    if isinstance(old, list) and isinstance(new, list) and len(old) == len(new):
        return [x for i, (a, b) in enumerate(zip(old, new)) for x in kept(a, b, f"{where}[{i}]")]
    return [] if old == new else [f"{where}: {old!r} -> {new!r}"]


def test_every_attempt_field_is_documented() -> None:
    assert list(ATTEMPT_FIELDS) and set(ATTEMPT_FIELDS) == {f.name for f in dataclasses.fields(AttemptRecord)}


@pytest.mark.parametrize("folder", ["oracle", "llm"])
def test_lines_written_before_records_were_typed_load_without_losing_a_key(folder: str) -> None:
    for line in lines(folder):
        rec = load_record(line)
        new = rec.to_dict()
        assert kept(line, new) == []  # every old key kept, value for value; added only the new keys
        assert set(new) - set(line) == {"schema", "error_type", "error_status"}
        assert EpisodeRecord.from_dict(rec.to_dict()) == rec  # and today's form reads back strictly


def test_old_llm_records_read_as_attributes() -> None:
    recs, bad = read_records(OLD / "llm" / "episodes.jsonl")
    assert bad == 0 and [r.failure for r in sorted(recs, key=lambda r: r.seed)] == [
        "motion", "unknown_object", "syntax", "no_code"]
    first = min(recs, key=lambda r: r.seed)
    assert first.llm is not None and first.llm.reporter == "text" and len(first.llm_attempts) == 2
    a1, a2 = first.llm_attempts
    assert a1.error == "PlanError: no code in completion" and a1.failed_program == "planner"
    assert a2.reset and a2.api_error is not None and a2.api_error.fn == "put_first_on_second"
    assert first.llm.spend is not None and first.llm.spend.tokens > 0


def _holds(new: object, old: object) -> bool:
    """``new`` has every key of ``old`` (recursively) with the same value."""
    if isinstance(old, dict):
        return isinstance(new, dict) and all(k in new and _holds(new[k], v) for k, v in old.items())
    return new == old


@pytest.mark.parametrize("folder", ["oracle", "llm"])
def test_old_folders_summarise_as_they_did(folder: str) -> None:
    """Every figure of a /1 summary is the same today (no anomaly in these runs); /2 only adds keys."""
    stored = json.loads((OLD / folder / "summary.json").read_text())
    stored.pop("run")
    now = json.loads(json.dumps(summarize_dir(OLD / folder)))
    assert stored.pop("schema") == "capmj.bench-summary/1" and now.pop("schema") == "capmj.bench-summary/2"
    assert set(now) - set(stored) == {"anomalies", "profile", "comparisons"} and now["anomalies"]["count"] == 0
    assert _holds(now, stored)
    cell = next(iter(now["overall"].values()))
    assert set(cell) - set(next(iter(stored["overall"].values()))) == {"episodes", "anomalies", "anomaly_labels",
                                                                       "denominator"}


def test_replay_lists_the_failed_episodes_of_an_old_folder() -> None:
    failed, total = failed_episodes(OLD / "llm")
    assert total == 4 and [e.seed for e in failed] == [10001, 10003, 10005, 10007]
    assert all(e.why and e.rrd is None for e in failed)


def test_strict_reading_names_the_bad_key() -> None:
    good = load_record(lines("llm")[0]).to_dict()
    with pytest.raises(RecordError, match="unknown key.*'colour'"):
        EpisodeRecord.from_dict({**good, "colour": "red"})
    del good["seed"]
    with pytest.raises(RecordError, match="missing key 'seed'"):
        EpisodeRecord.from_dict(good)
    attempt = load_record(lines("llm")[0]).llm_attempts[0].to_dict()
    with pytest.raises(RecordError, match=r"AttemptRecord\.primitives: expected int, got bool"):
        AttemptRecord.from_dict({**attempt, "primitives": True})
    with pytest.raises(RecordError, match="newer capmj"):
        load_record({**lines("oracle")[0], "schema": "capmj.episode/999"})


def test_legacy_attempt_fields_are_migrated() -> None:
    old = {"task": "t", "seed": 1, "agent": "llm", "model": "m", "success": False, "error": None,
           "llm": {"attempts": [{"attempt": 1, "extra_request": True, "predicate_success": {"success": True}}]}}
    rec = load_record(old)
    (a,) = rec.llm_attempts
    assert (a.extra_requests, a.predicate) == (1, True) and rec.llm is not None and rec.llm.model == "m"
    assert rec.failure == "wrong_plan"  # a line without a label is labelled when loaded


def test_a_new_run_writes_versioned_lines_without_inline_calls(tmp_path: Path) -> None:
    out = tmp_path / "run"
    assert main(["--agent", "oracle", "--tasks", "stack-all-blocks-on-a-zone", "--seeds", "10001", "--workers", "0",
                 "--no-log", "--no-progress", "--out", str(out)]) == 0
    (line,) = [json.loads(x) for x in (out / "episodes.jsonl").read_text().splitlines()]
    assert line["schema"] == SCHEMA and "calls" not in line and line["failure"] is None and line["llm"] == {}
    rec = EpisodeRecord.from_dict(line)
    assert rec.success and rec.drift is not None and rec.drift.max_m < 0.01
    assert EpisodeResult.from_dict({k: v for k, v in line.items() if k not in ("schema", "failure")} | {"calls": []})


def test_old_lines_get_error_types_from_their_text_and_keep_their_labels() -> None:
    for line in lines("llm"):
        rec = load_record(line)
        assert rec.error_type is not None and all(a.error_type for a in rec.llm_attempts if a.error)
        unlabelled = {k: v for k, v in line.items() if k != "failure"}
        assert load_record(unlabelled).failure == line["failure"]  # re-classified from the migrated types
    motion = load_record(next(x for x in lines("llm") if x["failure"] == "motion"))
    assert (motion.error_type, motion.error_status) == ("MotionFailed", "unreachable")


def test_v1_lines_are_migrated_strictly() -> None:
    v1 = {k: v for k, v in load_record(lines("llm")[1]).to_dict().items() if k not in ("error_type", "error_status")}
    for a in v1["llm"]["attempts"]:
        a.pop("error_type", None), a.pop("error_status", None)
    rec = load_record({**v1, "schema": "capmj.episode/1"})
    assert rec.error_type == "UnknownObjectError" and rec.failure == "unknown_object"
    with pytest.raises(RecordError, match="unknown key"):
        load_record({**v1, "schema": "capmj.episode/1", "colour": "red"})


def test_attribution_switches_on_the_recorded_class_not_the_message() -> None:
    rec = load_record(next(x for x in lines("llm") if x["failure"] == "unknown_object"))
    last = rec.llm_attempts[-1]
    assert "unknown object" in (last.error or "") and classify(rec) == "unknown_object"
    as_index = dataclasses.replace(last, error_type="IndexError", api_error=None)
    retyped = dataclasses.replace(rec, llm=dataclasses.replace(rec.llm, attempts=(rec.llm_attempts[0], as_index)))
    assert classify(retyped) == "plan_exception"  # same text, another class: another label
    sandbox = dataclasses.replace(as_index, error_type="SandboxViolation")
    assert classify(dataclasses.replace(rec, llm=dataclasses.replace(rec.llm, attempts=(sandbox,)))) == \
        "sandbox_violation"


def test_error_facts_follow_the_sandbox_wrapper_to_the_cause() -> None:
    try:
        try:
            raise MotionFailed("put_first_on_second('x') failed: no_grip: nothing there", status="no_grip")
        except MotionFailed as exc:
            raise PlanError("line 1 of the plan: ...") from exc
    except PlanError as wrapped:
        assert error_facts(wrapped) == ("MotionFailed", "no_grip")
    assert error_facts(PlanError("x")) == ("PlanError", None)
    # a class new to the tree keeps the text (and repr) of the class it was raised as before
    violation = SandboxViolation("SandboxViolation: import statements are not allowed", line=1)
    assert describe(violation) == "PlanError: line 1: SandboxViolation: import statements are not allowed"
    assert repr(MotionFailed("m", status="s")) == "RuntimeError('m')" and isinstance(MotionFailed("m", status="s"),
                                                                                         RuntimeError)


def test_v2_lines_written_before_loop_policies_read_strictly_as_the_thesis_loop() -> None:
    line = load_record(lines("llm")[0]).to_dict()
    for key in ("loop_policy", "reporter_prompt"):
        del line["llm"][key]
    for a in line["llm"]["attempts"]:
        for key in ("rule", "confidence", "low_confidence"):
            del a[key]
    rec = EpisodeRecord.from_dict(line)  # strict: these keys alone may be missing
    assert rec.llm is not None and (rec.llm.loop_policy, rec.llm.reporter_prompt) == ("thesis", "thesis")
    assert all(a.rule is None for a in rec.llm_attempts)
    del line["llm"]["attempts"][0]["verdict"]
    with pytest.raises(RecordError, match="missing key 'verdict'"):
        EpisodeRecord.from_dict(line)
