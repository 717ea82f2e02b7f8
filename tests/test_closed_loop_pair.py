"""``benchmarks/closed_loop_pair.py``: the with/without-reporter digest of issue #26 reads the
attempt records the LLM agent writes (``AttemptRecord.to_dict``) and scores verdicts against the
predicate on the same state."""

from __future__ import annotations

import json
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
from module_loader import ROOT, load_module

from capmj.records.attempt import AttemptRecord
from capmj.records.episode import EpisodeRecord
from capmj.records.notes import LLMNotes

def load_script() -> ModuleType:
    return load_module(ROOT / "benchmarks" / "closed_loop_pair.py")


def write_run(folder: Path, episodes: list[tuple[str, bool, list[AttemptRecord]]]) -> Path:
    """A bench result folder of real episode records, the last line cut short as by a running bench."""
    folder.mkdir()
    lines = [json.dumps(EpisodeRecord(
        task, 1, "llm", "openai/stub", ok, 1.0 if ok else 0.0, 0.0, 0, len(attempts), 0.0, 2.0, None,
        llm=LLMNotes("openai/stub", attempts=tuple(attempts), prompt_tokens=10, completion_tokens=5),
        failure=None if ok else "wrong_plan").to_dict()) for task, ok, attempts in episodes]
    (folder / "episodes.jsonl").write_text("\n".join(lines) + "\n" + lines[0][:40])
    return folder


def test_the_pair_digest_scores_verdicts_against_the_predicate_and_pairs_the_episodes(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    finished = AttemptRecord(1, predicate=True, rule="finished")
    none = write_run(tmp_path / "none", [("a", True, [finished]), ("b", False, [AttemptRecord(1, rule="finished")]),
                                         ("c", False, [AttemptRecord(1, rule="finished")])])
    fn = AttemptRecord(1, verdict=False, verdict_source="code", predicate=True, confidence="high", rule="partial_replan")
    tn = AttemptRecord(1, verdict=False, verdict_source="code", predicate=False, confidence="high", rule="not_achieved")
    tp = AttemptRecord(2, verdict=True, verdict_source="code", predicate=True, confidence="high", rule="achieved")
    unknown = AttemptRecord(1, verdict=None, verdict_source="unknown", predicate=False, confidence="low",
                            low_confidence="no_verdict", rule="low_confidence_stop")
    fp = AttemptRecord(1, verdict=True, verdict_source="direct", predicate=False, confidence="low",
                       rule="low_confidence_stop")
    text = write_run(tmp_path / "text", [("a", False, [fn, AttemptRecord(2, rule="error")]), ("b", True, [tn, tp]),
                                         ("c", False, [unknown]), ("d", False, [fp])])
    assert load_script().main([str(none), str(text)]) == 0
    out: dict[str, Any] = json.loads(capsys.readouterr().out)
    with_reporter = out["runs"][str(text)]
    assert with_reporter["verdicts_vs_predicate"] == {"judged": 5, "agree": 2, "fp": 1, "fn": 1, "unknown": 1,
                                                      "high_confidence": 3}
    assert out["runs"][str(none)]["verdicts_vs_predicate"]["judged"] == 0
    assert with_reporter["rules"]["low_confidence_stop"] == 2 and with_reporter["success"] == 1
    assert out["paired"]["episodes"] == 3  # "d" ran only with the reporter
    assert (out["paired"]["only_a"], out["paired"]["only_b"]) == (["a 1"], ["b 1"])
    assert out["paired"]["p_value"] == 1.0
