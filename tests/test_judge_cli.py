"""``python -m capmj.bench judge`` end to end, with the reporter's LLM calls answered by the scripted
local server (tests/llm_stub_server.py).  The scripted answers are fixtures, never results: they
exist to show that the metrics behave (an always-yes reporter must score recall 1 and precision =
the positive share) and that verdict sources and tokens are counted."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from llm_stub_server import StubLLMServer, prompt_text

from capmj.bench.cli import main
from capmj.judge.metrics import confusion, contrast_counts, metrics

TASKS = "stack-blocks-with-alternate-color,put-block-into-matching-bowl"
SEEDS = "10001"


def code(text: str) -> str:
    return f"```python\n{text.strip()}\n```"


def lmp_of(request: dict[str, Any]) -> str:
    text = prompt_text(request)
    if "You check from a list of object poses" in text:
        return "reporter_direct"
    if "Judge whether the goal in the last comment" in text:
        return "parse_completion"
    raise AssertionError(f"unexpected request: {text[:200]!r}")


def judge(tmp_path: Path, *extra: str) -> tuple[int, dict[str, Any], list[dict[str, Any]]]:
    out = tmp_path / "out"
    rc = main(["judge", "--tasks", TASKS, "--seeds", SEEDS, "--out", str(out), "--no-progress", *extra])
    if rc != 0:
        return rc, {}, []
    summary = json.loads((out / "summary.json").read_text())
    judged = [json.loads(line) for line in (out / "judged.jsonl").read_text().splitlines()]
    return rc, summary, judged


def llm_flags(server: StubLLMServer) -> list[str]:
    return ["--reporter", "text", "--model", "openai/stub", "--api-base", server.base_url, "--llm-timeout", "10"]


def test_an_always_yes_reporter_scores_recall_one_and_precision_the_positive_share(
        server: StubLLMServer, tmp_path: Path) -> None:
    seen: list[str] = []

    def always_yes(request: dict[str, Any]) -> str:
        seen.append(lmp_of(request))
        return code("judge = True\nreason = 'looks done'")

    server.respond_with(always_yes)
    rc, s, judged = judge(tmp_path, *llm_flags(server))
    assert rc == 0
    o = s["overall"]
    assert o["n"] == len(judged) == s["cases"] and o["n"] >= 8
    assert 0 < o["positives"] < o["n"]
    assert o["recall"] == 1.0 and o["specificity"] == 0.0 and o["balanced_accuracy"] == 0.5
    assert o["precision"] == pytest.approx(o["positives"] / o["n"]) == o["positive_share"] == o["accuracy"]
    assert o["verdict_rate"] == 1.0 and o["verdict_sources"]["code"] == o["n"]
    assert seen == ["parse_completion"] * o["n"] and o["calls"] == o["n"]
    assert o["prompt_tokens"] > 0 and o["completion_tokens"] > 0 and o["label_mismatches"] == 0
    for task, m in s["tasks"].items():
        assert m["recall"] == 1.0 and m["precision"] == pytest.approx(m["positives"] / m["n"]), task
    assert s["kinds"]["oracle"]["accuracy"] == 1.0 and s["kinds"]["swapped"]["accuracy"] == 0.0
    md = (tmp_path / "out" / "summary.md").read_text()
    assert "| **overall** |" in md and "stack-blocks-with-alternate-color" in md


def test_the_predicate_reporter_is_always_right_on_states_that_keep_their_labels(tmp_path: Path) -> None:
    rc, s, judged = judge(tmp_path, "--reporter", "predicate")
    assert rc == 0
    assert s["overall"]["accuracy"] == 1.0 and s["overall"]["balanced_accuracy"] == 1.0
    assert all(r["predicate"] == r["label"] for r in judged) and s["overall"]["calls"] == 0
    cases = [json.loads(line) for line in (tmp_path / "out" / "cases.jsonl").read_text().splitlines()]
    assert [(c["task"], c["case"]) for c in cases] == [(r["task"], r["case"]) for r in judged]


def test_a_killed_judge_keeps_every_state_judged_so_far(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from capmj.judge.evaluate import Judge

    real, seen = Judge.judge, []

    def judge_then_die(self: Judge, case: Any) -> Any:
        if len(seen) == 2:
            raise KeyboardInterrupt  # the user's Ctrl-C, or a killed session, in the third state
        seen.append(case.case)
        return real(self, case)

    monkeypatch.setattr(Judge, "judge", judge_then_die)
    with pytest.raises(KeyboardInterrupt):
        judge(tmp_path, "--reporter", "predicate")
    kept = [json.loads(line) for line in (tmp_path / "out" / "judged.jsonl").read_text().splitlines()]
    assert [r["case"] for r in kept] == seen and all(r["correct"] for r in kept)
    assert len((tmp_path / "out" / "transcripts.jsonl").read_text().splitlines()) == 2
    assert not (tmp_path / "out" / "summary.json").exists()


def test_failing_checking_code_falls_back_to_the_direct_verdict_and_the_sources_say_so(
        server: StubLLMServer, tmp_path: Path) -> None:
    def broken_then_no(request: dict[str, Any]) -> str:
        if lmp_of(request) == "parse_completion":
            return code("judge = undefined_name")  # NameError, also after the repair request
        return code("judge = False\nreason = 'not done'")

    server.respond_with(broken_then_no)
    rc, s, judged = judge(tmp_path, *llm_flags(server))
    assert rc == 0
    o = s["overall"]
    assert o["verdict_sources"]["direct"] == o["n"] and o["verdict_sources"]["code"] == 0
    assert o["recall"] == 0.0 and o["specificity"] == 1.0 and o["precision"] is None
    assert o["calls"] == 3 * o["n"]  # code, repair, direct
    assert all(any("NameError" in e for e in r["errors"]) for r in judged)


def test_answers_without_a_verdict_stay_unknown_and_count_as_wrong(server: StubLLMServer, tmp_path: Path) -> None:
    server.respond_with(lambda request: "no code here")  # parse_completion, repair, direct: no verdict anywhere
    rc, s, _ = judge(tmp_path, *llm_flags(server), "--kinds", "oracle,swapped")
    assert rc == 0
    o = s["overall"]
    assert o["verdict_rate"] == 0.0 and o["accuracy"] == 0.0 and o["verdict_sources"]["unknown"] == o["n"]


def test_bad_input_is_one_line_naming_the_valid_choices(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["judge", "--tasks", TASKS, "--seeds", SEEDS, "--out", str(tmp_path), "--reporter", "text"]) == 2
    assert "--reporter text needs --model" in capsys.readouterr().err
    assert main(["judge", "--tasks", TASKS, "--seeds", SEEDS, "--out", str(tmp_path), "--reporter", "predicate",
                 "--kinds", "oracle,tipped", "--no-progress"]) == 2
    assert "valid kinds: oracle, displaced" in capsys.readouterr().err


def test_metrics_by_hand() -> None:
    recs = ([{"label": True, "verdict": True}] * 3 + [{"label": True, "verdict": False}]
            + [{"label": True, "verdict": None}] + [{"label": False, "verdict": False}] * 4
            + [{"label": False, "verdict": True}])
    assert confusion(recs) == {"tp": 3, "fn": 1, "fp": 1, "tn": 4, "unknown_pos": 1, "unknown_neg": 0}
    m = metrics(recs)
    assert (m["n"], m["positives"], m["negatives"]) == (10, 5, 5)
    assert m["accuracy"] == 0.7 and m["recall"] == 0.6 and m["specificity"] == 0.8 and m["precision"] == 0.75
    assert m["balanced_accuracy"] == pytest.approx(0.7) and m["verdict_rate"] == 0.9
    lo, hi = m["accuracy_ci"]
    assert lo == pytest.approx(0.3968, abs=1e-4) and hi == pytest.approx(0.8922, abs=1e-4)


def test_contrasts_count_episodes_told_apart_and_episodes_judged_blind_to_the_state() -> None:
    def rec(task: str, seed: int, label: bool, verdict: bool | None) -> dict[str, object]:
        return {"task": task, "seed": seed, "label": label, "verdict": verdict}

    recs = [rec("a", 1, True, True), rec("a", 1, False, False), rec("a", 1, False, False),  # told apart
            rec("a", 2, True, False), rec("a", 2, False, False),                           # blind: both no
            rec("b", 1, True, None), rec("b", 1, False, None),                             # blind: unknown
            rec("b", 2, True, True), rec("b", 2, False, True), rec("b", 2, False, False),  # neither
            rec("c", 1, True, True)]                                                       # no negative
    assert contrast_counts(recs) == {"contrasts": 4, "contrasts_told_apart": 1, "contrasts_state_blind": 2}
    m = metrics(recs)
    assert (m["contrasts"], m["contrasts_told_apart"], m["contrasts_state_blind"]) == (4, 1, 2)
    assert contrast_counts([rec("a", 1, True, True), rec("a", 2, False, False)])["contrasts"] == 0


def test_report_compares_two_scripted_reporters_on_the_same_states_with_mcnemar(
        server: StubLLMServer, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    kinds = ["--kinds", "oracle,displaced,unstacked,toppled,swapped,wrong_bowl"]
    for name, answer in (("yes", "judge = True"), ("no", "judge = False")):
        server.respond_with(lambda request, a=answer: code(a))
        out = tmp_path / name
        assert main(["judge", "--tasks", TASKS, "--seeds", SEEDS, "--out", str(out), "--no-progress",
                     *llm_flags(server), *kinds]) == 0
    assert main(["judge", "report", str(tmp_path / "yes"), str(tmp_path / "no"), "--out", str(tmp_path / "cmp")]) == 0
    result = json.loads((tmp_path / "cmp" / "comparison.json").read_text())
    o = result["overall"]
    # 2 positives (the oracle states: only "yes" is right) and 6 negatives (only "no" is right)
    assert (o["n"], o["only_a"], o["only_b"], result["unpaired"], result["same_set"]) == (8, 2, 6, 0, True)
    assert o["p_value"] == pytest.approx(2 * (1 + 8 + 28) / 2 ** 8)  # 2 * P[Binomial(8, 1/2) <= 2]
    assert "| **overall** | 8 | 2 | 6 | 2 | 6 | 0.289 (n.s.) |" in capsys.readouterr().out
    assert main(["judge", "report", str(tmp_path / "yes"), str(tmp_path / "missing")]) == 2


def test_log_writes_one_rrd_per_judged_state_with_the_transcript_and_the_label(
        server: StubLLMServer, tmp_path: Path) -> None:
    from capmj.replay import read_episode

    server.respond_with(lambda request: code("judge = True\nreason = 'scripted'"))
    out = tmp_path / "out"
    assert main(["judge", "--tasks", "stack-blocks-with-alternate-color", "--seeds", SEEDS, "--out", str(out),
                 "--no-progress", "--kinds", "oracle,swapped", "--log", *llm_flags(server)]) == 0
    swapped = read_episode(out / "rrd" / "stack-blocks-with-alternate-color" / f"{SEEDS}-swapped.rrd")
    assert swapped.summary["success"] is False  # the label, not the reporter's verdict
    assert "judge = True" in swapped.texts["llm/attempt1/parse_completion/1/completion"][0]
    assert swapped.texts["verdict"][0].startswith("label: not achieved (swapped: ")
    assert (out / "rrd" / "stack-blocks-with-alternate-color" / f"{SEEDS}-oracle.rrd").stat().st_size > 0


def test_judge_takes_the_bench_llm_flags(tmp_path: Path) -> None:
    from capmj.bench.cli import build_parser as bench_parser
    from capmj.judge.cli import build_parser as judge_parser
    from capmj.llm.options import llm_values

    flags = ["--model", "openai/x", "--api-base", "http://127.0.0.1:1/v1", "--llm-timeout", "42",
             "--llm-max-tokens", "99", "--llm-cache", str(tmp_path), "--temperature", "0.5"]
    judged = llm_values(judge_parser().parse_args(["--out", str(tmp_path), *flags]))
    assert judged == llm_values(bench_parser().parse_args(["--agent", "llm", *flags]))


def test_from_a_run_judges_its_final_states_labelled_by_the_predicate(tmp_path: Path) -> None:
    run = tmp_path / "run"
    assert main(["--tasks", "put-block-into-matching-bowl", "--seeds", SEEDS, "--agent", "oracle", "--workers", "0",
                 "--no-log", "--no-progress", "--out", str(run)]) == 0
    solved = json.loads((run / "episodes.jsonl").read_text().splitlines()[0])
    assert solved["success"] is True
    spoiled = json.loads(json.dumps(solved))  # the same episode with one block moved off its bowl
    block = next(n for n in spoiled["final_poses"] if " block " in n)
    spoiled["final_poses"][block][:3] = [0.65, 0.38, 0.02]
    with (run / "episodes.jsonl").open("a") as f:
        f.write(json.dumps(spoiled) + "\n" + json.dumps({"task": solved["task"], "seed": 1}) + "\n")
    out = tmp_path / "out"
    assert main(["judge", "--tasks", "put-block-into-matching-bowl", "--seeds", SEEDS, "--kinds", "oracle",
                 "--from", str(run), "--reporter", "predicate", "--out", str(out), "--no-progress"]) == 0
    cases = [json.loads(line) for line in (out / "cases.jsonl").read_text().splitlines()]
    runs = [c for c in cases if c["kind"] == "run"]
    assert [(c["case"], c["label"]) for c in runs] == [("run1", True), ("run2", False)]
    assert "is not in the" in runs[1]["condition"]
    skipped = [json.loads(line) for line in (out / "skipped.jsonl").read_text().splitlines()]
    assert any(s["kind"] == "run" and "no final_poses" in s["reason"] for s in skipped)
    kinds = json.loads((out / "summary.json").read_text())["kinds"]
    assert kinds["run"]["n"] == 2 and kinds["run"]["accuracy"] == 1.0
    only = tmp_path / "only"  # --kinds run: the run's states alone, no synthetic set
    assert main(["judge", "--tasks", "put-block-into-matching-bowl", "--seeds", SEEDS, "--kinds", "run",
                 "--from", str(run), "--reporter", "predicate", "--out", str(only), "--no-progress"]) == 0
    assert [c["case"] for c in map(json.loads, (only / "cases.jsonl").read_text().splitlines())] == ["run1", "run2"]
    assert json.loads((only / "summary.json").read_text())["pairs"] == 1  # the episodes judged, not --tasks x --seeds
    assert main(["judge", "--kinds", "run", "--reporter", "predicate", "--out", str(only), "--no-progress"]) == 2


def test_summarize_rewrites_a_finished_summary_byte_for_byte_and_summarizes_a_killed_run(tmp_path: Path) -> None:
    out = tmp_path / "out"
    assert main(["judge", "--tasks", TASKS, "--seeds", SEEDS, "--out", str(out), "--reporter", "predicate",
                 "--kinds", "oracle,displaced", "--no-progress"]) == 0
    finished = (out / "summary.json").read_bytes()
    assert main(["judge", "summarize", str(out)]) == 0
    assert (out / "summary.json").read_bytes() == finished
    lines = (out / "judged.jsonl").read_text().splitlines()
    assert len(lines) >= 2
    (out / "judged.jsonl").write_text(lines[0] + "\n")  # a run killed after its first state
    for name in ("summary.json", "summary.md", "config.json"):
        (out / name).unlink()
    assert main(["judge", "summarize", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["overall"]["n"] == 1 and summary["cases"] == len(lines)
    assert summary["stopped"] == f"interrupted: 1 of {len(lines)} states judged (summarized from judged.jsonl)"
    assert "**Stopped early:** interrupted" in (out / "summary.md").read_text()
    assert main(["judge", "summarize", str(tmp_path / "nothing")]) == 2
