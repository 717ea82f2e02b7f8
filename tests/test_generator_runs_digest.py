"""``benchmarks/generator_runs.py``: the digest of real generator runs (issue #27 item 4) reads the
records the generator writes (``CandidateRecord.to_dict``) and sorts each stop by whose fault it is."""

from __future__ import annotations

import json
from pathlib import Path
from types import ModuleType

import pytest
from module_loader import ROOT, load_module

from capmj.generate.candidate import CandidateRecord

def load_script() -> ModuleType:
    return load_module(ROOT / "benchmarks" / "generator_runs.py")


def test_the_digest_counts_stages_reached_and_whose_fault_each_stop_was(tmp_path: Path,
                                                                         capsys: pytest.CaptureFixture[str]) -> None:
    records = [
        CandidateRecord(0, "bottom-up", stage="static", reason="static check parse failed after the repair round",
                        checks=[{"stage": "static", "attempt": 2, "name": "parse", "outcome": "fail", "detail": ""}],
                        wall_s={"total": 30.0}),
        CandidateRecord(1, "bottom-up", stage="write", reason="write: LLMError: Timeout: no token for 600 s",
                        wall_s={"total": 600.0}),
        CandidateRecord(2, "bottom-up", stage="accepted", accepted=True, reason="all checks passed",
                        wall_s={"total": 90.0}, usage={"calls": 5, "prompt_tokens": 100, "completion_tokens": 10}),
        CandidateRecord(3, "bottom-up", stage="runtime", reason="runtime check oracle_solves: 0/3",
                        checks=[{"stage": "runtime", "attempt": 1, "name": "oracle_solves", "outcome": "fail"}],
                        wall_s={"total": 60.0}),
    ]
    journal = tmp_path / "run" / "generation.jsonl"
    journal.parent.mkdir()
    journal.write_text("".join(json.dumps(r.to_dict()) + "\n" for r in reversed(records)))
    script = load_script()
    assert script.main([str(journal)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["candidates"] == 4 and [r["index"] for r in out["rows"]] == [0, 1, 2, 3]
    assert out["reached"] == {"propose": 4, "examples": 4, "write": 4, "static": 3, "runtime": 2,
                              "reflection": 1, "accepted": 1}
    assert out["stopped_by"] == {"model": 2, "capmj": 1, "accepted": 1}
    assert out["failed_checks"] == {"static/parse": 1, "runtime/oracle_solves": 1}
    assert out["wall_s_per_candidate"] == {"median": 90.0, "max": 600.0}
    assert out["rows"][2]["calls"] == 5 and out["rows"][1]["stopped_by"] == "capmj"
    assert script.main([str(tmp_path / "missing.jsonl")]) == 2
