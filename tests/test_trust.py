"""Results a reviewer trusts: failure labels, McNemar, budgets, manifest, replay-check, export.

LLM answers are scripted fixtures served by the local HTTP stub server (tests/llm_stub_server.py);
physics, sandbox, prompts, cache and the bench CLI are real.  Plans are kept to at most one
pick-and-place where the label allows, to keep the CPU cost low.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any, Iterator

import pytest

from capmj.agents.llm_agent.agent import LLMAgent
from capmj.agents.sandbox import SandboxBudget
from capmj.bench.cli import main
from capmj.bench.failures import LABELS, classify
from capmj.bench.migrate import load_record
from capmj.bench.stats import mcnemar_exact, paired_comparison
from capmj.runner import run_episode
from capmj.tasks.registry import get_task
from llm_stub_server import Reply, StubLLMServer
from test_llm_chain import OBJ_NAMES, REPORTER, RIGHT_PLAN, SEED, TASK, Router, code, parse_function_answer

BLOCK, ORANGE, PURPLE = "movable small cyan block with obj_id 3", "fixed orange zone with obj_id 1", \
    "fixed purple zone with obj_id 2"


@pytest.fixture
def server() -> Iterator[StubLLMServer]:
    with StubLLMServer() as stub:
        yield stub


def label_of(server: StubLLMServer, planner: Any, **kw: Any) -> tuple[str | None, dict[str, Any]]:
    handlers = {"planner": planner, "parse_obj_name": code(OBJ_NAMES), "parse_function": parse_function_answer}
    handlers.update(kw.pop("handlers", {}))
    server.respond_with(Router(**handlers))
    kw.setdefault("backoff_s", 0.0)
    kw.setdefault("timeout_s", 10.0)
    agent = LLMAgent.from_options(model="openai/stub", api_base=server.base_url, **kw)  # the bench's flat options
    result = run_episode(get_task(TASK), SEED, agent)
    return classify(result), result.to_dict()


# ------------------------------------------------------------------------------------------------
# every label from a scripted completion or a scripted physical event
# ------------------------------------------------------------------------------------------------
CHEAP = {  # label: planner answer (no pick-and-place happens)
    "no_code": "I cannot help with that.",
    "syntax": code("for block in\n    put_first_on_second(block)"),
    "sandbox_violation": code("import os\nos.system('echo hi')"),
    "budget": code("while True:\n    pass"),
    "unknown_object": code(f"put_first_on_second('the green block', '{ORANGE}')"),  # no green object
    "api_misuse": code(f"put_first_on_second(3.5, '{ORANGE}')"),
    "plan_exception": code("blocks = []\nfirst = blocks[0]"),
    "helper_lmp": code("blocks = parse_obj_name('all the blocks', f'objects = {get_obj_names()}')\nsay(blocks)"),
    "motion": code(f"put_first_on_second([2.0, 0.0], '{ORANGE}')"),
}


@pytest.mark.parametrize("label", list(CHEAP))
def test_failure_label_of_a_failing_plan(server: StubLLMServer, label: str) -> None:
    handlers = {"parse_obj_name": code("ret_val = [")} if label == "helper_lmp" else {}
    budget = {"plan_budget": SandboxBudget(wall_s=0.5, max_api_calls=100)} if label == "budget" else {}
    got, rec = label_of(server, CHEAP[label], handlers=handlers, **budget)
    assert got == label, (rec["error"], rec["llm"]["attempts"])
    assert rec["success"] is False and rec["primitives"] == (1 if label == "motion" else 0)


def test_llm_error_label(server: StubLLMServer) -> None:
    got, rec = label_of(server, Reply.error(500, "down"), max_retries=0)
    assert got == "llm_error" and rec["error"].startswith("LLMError")


def test_wrong_plan_physics_and_reporter_false_positive(server: StubLLMServer) -> None:
    wrong = code(f"put_first_on_second('{BLOCK}', '{PURPLE}')")
    got, rec = label_of(server, wrong)
    assert got == "wrong_plan" and rec["error"] is None and rec["primitives"] == 1
    assert rec["drift"]["max_m"] < 0.005
    # the block is let go 25 cm above the orange zone: the primitive succeeds, then it falls
    dropped = code(f"x, y, _ = get_obj_pos('{ORANGE}')\nput_first_on_second('{BLOCK}', [x, y, 0.3])")
    got, rec = label_of(server, dropped)
    assert got == "physics" and rec["error"] is None and rec["drift"]["objects"][BLOCK] > 0.2
    # a reporter that says "achieved" for the wrong plan ends the loop with attempts left
    got, rec = label_of(server, wrong, reporter="text", attempts=2,
                        handlers={"parse_completion": code("judge = True\nreason = 'looks done'")})
    assert got == "reporter_false_positive" and len(rec["llm"]["attempts"]) == 1
    assert rec["llm"]["attempts"][0]["predicate"] is False


def test_reporter_false_negative(server: StubLLMServer) -> None:
    def planner(request: dict[str, Any]) -> str:  # right first, then prose
        return code(RIGHT_PLAN) if len(request["messages"]) == 2 else "I give up."

    got, rec = label_of(server, planner, reporter="text", attempts=2,
                        handlers={"parse_completion": code(REPORTER.replace("judge = ", "judge = not "))})
    first, second = rec["llm"]["attempts"]
    assert first["predicate"] is True and first["verdict"] is False and "no code" in second["error"]
    assert got == "reporter_false_negative"


@pytest.mark.parametrize("limit", ["tokens", "cost"])
def test_episode_llm_budget_ends_the_episode_as_budget(server: StubLLMServer, limit: str) -> None:
    kw: dict[str, Any] = ({"episode_max_tokens": 50} if limit == "tokens"
                          else {"episode_max_cost_usd": 0.01, "price": "1000,1000"})
    got, rec = label_of(server, code("say('hi')"), attempts=3, **kw)
    assert got == "budget" and rec["llm"]["stopped"] == "llm budget"
    assert len(server.requests) == 1 and f"{'token' if limit == 'tokens' else 'cost'} budget of" in rec["error"]
    spend = rec["llm"]["spend"]
    assert spend["tokens"] > 50
    if limit == "tokens":
        assert spend["cost_usd"] is None and spend["price_source"] == "unknown"
    else:
        assert spend["cost_usd"] == pytest.approx(spend["tokens"] * 1000 / 1e6) and spend["cost_usd"] > 0.01


def test_labels_are_documented() -> None:
    doc = (Path(__file__).resolve().parents[1] / "docs" / "failures.md").read_text()
    for label in LABELS:
        assert f"`{label}`" in doc, label


# ------------------------------------------------------------------------------------------------
# McNemar
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("b", "c", "p"), [
    (0, 0, 1.0),
    (1, 6, 2 * (1 + 7) / 2 ** 7),                 # 0.125
    (0, 5, 2 / 2 ** 5),                           # 0.0625: 5 discordant pairs can never be significant
    (2, 10, 2 * (1 + 12 + 66) / 2 ** 12),         # 0.0386
    (3, 3, 1.0),
    (0, 6, 2 / 2 ** 6),                           # 0.03125
])
def test_mcnemar_exact_matches_hand_computation(b: int, c: int, p: float) -> None:
    assert mcnemar_exact(b, c) == pytest.approx(p, rel=1e-12)
    assert mcnemar_exact(c, b) == pytest.approx(p, rel=1e-12)


def test_paired_comparison_counts_only_common_pairs() -> None:
    recs = []
    for seed in range(8):  # A wins on 6 seeds, B on 1, one tie; seed 99 only A ran
        recs.append(load_record({"task": "t", "seed": seed, "agent": "A", "success": seed != 7}))
        recs.append(load_record({"task": "t", "seed": seed, "agent": "B", "success": seed == 7}))
    recs.append(load_record({"task": "t", "seed": 99, "agent": "A", "success": True}))
    cmp = paired_comparison(recs, lambda r: r.agent, "A", "B")
    o = cmp["overall"]
    assert (o["n"], o["only_a"], o["only_b"], cmp["unpaired"]) == (8, 7, 1, 1)
    assert o["p_value"] == pytest.approx(2 * (1 + 8) / 2 ** 8) and not o["significant"]
    assert o["difference"] == pytest.approx(6 / 8)


# ------------------------------------------------------------------------------------------------
# the bench: run budget + resume, cost, manifest + report warnings, replay-check, export
# ------------------------------------------------------------------------------------------------
ONE_MOVE = code("blocks = parse_obj_name('all the blocks', f'objects = {get_obj_names()}')\n"
                "zone = [n for n in get_obj_names() if ' zone ' in n][-1]\n"
                "put_first_on_second(blocks[0], zone)")
SEEDS = "10001,10003"


@pytest.fixture(scope="module")
def stub() -> Iterator[StubLLMServer]:
    with StubLLMServer() as s:
        s.respond_with(Router(planner=ONE_MOVE, parse_obj_name=code(OBJ_NAMES)))
        yield s


def bench(stub: StubLLMServer, out: Path, *extra: str) -> int:
    return main(["--agent", "llm", "--model", "openai/stub", "--api-base", stub.base_url, "--tasks", TASK,
                 "--workers", "0", "--concurrency", "1",  # the run budget is checked between batches
                 "--no-log", "--no-progress", "--out", str(out), *extra])


@pytest.fixture(scope="module")
def run_a(stub: StubLLMServer, tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("trust")
    mp = pytest.MonkeyPatch()
    mp.setenv("CAPMJ_LLM_CACHE", str(root / "cache"))
    try:
        out = root / "a"
        # 1000 USD per million tokens: the first episode alone passes the 0.001 USD cap
        assert bench(stub, out, "--seeds", SEEDS, "--price", "1000,1000", "--max-cost-usd", "0.001") == 3
        assert len((out / "episodes.jsonl").read_text().splitlines()) == 1
        assert bench(stub, out, "--resume", "--price", "1000,1000", "--max-cost-usd", "100") == 0
    finally:
        mp.undo()
    return out


def _records(out: Path) -> list[dict[str, Any]]:
    return [json.loads(x) for x in (out / "episodes.jsonl").read_text().splitlines()]


def test_run_stopped_by_cost_resumes_to_completion_with_cost_in_the_summary(run_a: Path) -> None:
    recs = _records(run_a)
    assert sorted(r["seed"] for r in recs) == [10001, 10003]
    assert all(r["failure"] == "wrong_plan" and r["primitives"] == 1 for r in recs)
    summary = json.loads((run_a / "summary.json").read_text())
    u = summary["overall"]["llm openai/stub"]["llm_usage"]
    assert u["calls"] == 4 and u["cost_known"]
    assert u["cost_usd"] == pytest.approx(sum(r["llm"]["spend"]["cost_usd"] for r in recs))
    assert u["tokens"] == sum(r["llm"]["prompt_tokens"] + r["llm"]["completion_tokens"] for r in recs)
    assert summary["overall"]["llm openai/stub"]["failures"] == {"wrong_plan": 2}
    md = (run_a / "summary.md").read_text()
    assert "## Failures" in md and "## LLM usage and cost" in md and "(n=2)" in md
    cfg = json.loads((run_a / "config.json").read_text())
    # the first part's limit stays recorded; the resume's is a recorded change
    assert cfg["args"]["run_budget"]["max_cost_usd"] == 0.001 and cfg["manifest"]["price"]
    assert cfg["resumes"][-1]["changed"] == {"run_budget.max_cost_usd": {"from": 0.001, "to": 100}}


def test_unknown_price_is_unknown_and_cannot_cap_cost(stub: StubLLMServer, tmp_path: Path, capsys) -> None:
    assert bench(stub, tmp_path / "x", "--seeds", "1", "--max-cost-usd", "1") == 2
    assert "price" in capsys.readouterr().err
    from capmj.bench.spend import usage

    recs = [load_record({"task": "t", "seed": s, "agent": "llm", "llm": {"spend": spend}})
            for s, spend in enumerate([{"calls": 1, "tokens": 10, "cost_usd": None},
                                       {"calls": 1, "tokens": 5, "cost_usd": 0.5}])]
    assert usage(recs)["cost_usd"] is None and usage(recs)["tokens"] == 15


def test_run_budget_counts_the_whole_folder() -> None:
    from capmj.bench.spend import BudgetTracker, RunBudget

    ep = load_record({"task": "t", "seed": 1, "agent": "llm",
                      "llm": {"spend": {"calls": 2, "tokens": 600, "cost_usd": 0.25}}})
    tracker = BudgetTracker(RunBudget.resolve(None, None, {"max_tokens": 1000}), [ep])  # stored limit
    assert not tracker.stop()
    tracker.add(ep)
    assert tracker.stop() and "1200 LLM tokens" in tracker.reason
    assert not BudgetTracker(RunBudget(max_cost_usd=0.6), [ep, ep]).stop()
    assert BudgetTracker(RunBudget(max_cost_usd=0.5), [ep, ep]).stop()
    assert not BudgetTracker(RunBudget(), [ep] * 100).stop()


def test_manifest_records_the_run_and_report_warns_when_a_prompt_changed(
        run_a: Path, stub: StubLLMServer, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    from capmj.agents.prompt_files import prompts_dir

    m = json.loads((run_a / "config.json").read_text())["manifest"]
    assert m["model"] == "openai/stub" and m["api_host"].startswith("127.0.0.1:")
    assert "sk-" not in json.dumps(m) and set(m["prompts"]) >= {"planner.py", "system.txt"}
    assert any(k.startswith("capmj_tasks/") for k in m["task_modules"]) and m["packages"]["litellm"]
    assert m["budgets"]["plan_budget"]["wall_s"] > 0 and m["budgets"]["episode"]["max_sim_steps"] > 0
    edited = tmp_path / "prompts"
    shutil.copytree(prompts_dir(), edited)
    with open(edited / "system.txt", "a") as f:
        f.write("\nBe brief.\n")
    monkeypatch.setenv("CAPMJ_PROMPTS_DIR", str(edited))
    assert bench(stub, tmp_path / "b", "--seeds", "10001") == 0
    mb = json.loads((tmp_path / "b" / "config.json").read_text())["manifest"]
    assert mb["prompts"]["system.txt"] != m["prompts"]["system.txt"]
    assert mb["prompts"]["planner.py"] == m["prompts"]["planner.py"]
    capsys.readouterr()
    # the prompts are part of the task stamp: report refuses the two runs unless told to compare them (#49 item 4)
    assert main(["report", str(run_a), str(tmp_path / "b"), "--out", str(tmp_path / "cmp")]) == 2
    assert "stamps differ" in capsys.readouterr().err
    assert main(["report", str(run_a), str(tmp_path / "b"), "--out", str(tmp_path / "cmp"),
                 "--allow-version-mismatch"]) == 0
    out, err = capsys.readouterr()
    assert "warning: prompts.system.txt differs" in err and "prompts.planner.py" not in err
    assert "## Warnings: the combined runs differ" in out
    assert "## Paired comparison" in out and "not significant" in out
    cmp = json.loads((tmp_path / "cmp" / "summary.json").read_text())["comparisons"][0]
    assert cmp["overall"]["n"] == 1 and cmp["unpaired"] == 1 and cmp["overall"]["p_value"] == 1.0


def test_replay_check_passes_then_fails_on_an_edited_completion(run_a: Path, stub: StubLLMServer, capsys) -> None:
    before = len(stub.requests)
    assert main(["replay-check", str(run_a)]) == 0
    assert len(stub.requests) == before  # zero HTTP calls
    assert "2/2 episode(s) identical" in capsys.readouterr().out
    cache = Path(json.loads((run_a / "config.json").read_text())["manifest"]["cache_dir"])
    entry = next(p for p in sorted(cache.rglob("*.json")) if "put_first_on_second(blocks[0]" in p.read_text())
    data = json.loads(entry.read_text())
    data["text"] = data["text"].replace("blocks[0]", "blocks[1]")
    entry.write_text(json.dumps(data))
    assert main(["replay-check", str(run_a), "--json"]) == 1
    result = json.loads(capsys.readouterr().out)
    assert result["passed"] == 1 and result["http_calls"] == 0 and len(stub.requests) == before
    (bad,) = result["mismatches"]
    assert any("final pose" in r for r in bad["reasons"])
    entry.unlink()  # a missing entry is an error, never a live call
    assert main(["replay-check", str(run_a), "--json"]) == 1
    result = json.loads(capsys.readouterr().out)
    assert "missing cache entry" in result["mismatches"][0]["reasons"][0] and len(stub.requests) == before


def test_export_round_trips_and_matches_the_call_count(run_a: Path, tmp_path: Path) -> None:
    out = tmp_path / "calls.jsonl"
    assert main(["export", str(run_a), "--format", "chat-jsonl", "--out", str(out)]) == 0
    lines = out.read_text().splitlines()
    recs = _records(run_a)
    assert len(lines) == sum(r["llm"]["calls"] for r in recs) == 4
    for line in lines:
        ex = json.loads(line)
        assert json.dumps(ex, ensure_ascii=False) == line
        assert [m["role"] for m in ex["messages"]] == ["system", "user", "assistant"]
        assert ex["metadata"]["failure"] == "wrong_plan" and ex["metadata"]["episode_success"] is False
    lmps = sorted(json.loads(x)["metadata"]["lmp"] for x in lines)
    assert lmps == ["parse_obj_name", "parse_obj_name", "planner", "planner"]
    plans = [json.loads(x) for x in lines if json.loads(x)["metadata"]["lmp"] == "planner"]
    assert all("put_first_on_second(blocks[0]" in p["messages"][-1]["content"] for p in plans)
    assert main(["export", str(run_a), "--only-success", "--messages-only", "--out", str(out)]) == 0
    assert out.read_text() == ""


@pytest.mark.parametrize("label", ["unknown_object", "helper_lmp"])
def test_label_of_an_episode_whose_last_plan_was_not_rerun_is_that_of_the_attempt_it_repeats(
        server: StubLLMServer, label: str) -> None:
    handlers = {"parse_obj_name": code("ret_val = [")} if label == "helper_lmp" else {}
    got, rec = label_of(server, CHEAP[label], handlers=handlers, attempts=2, replan_retries=1)
    first, second = rec["llm"]["attempts"]
    assert second["not_run"] == "identical to attempt 1 after 1 retries; not re-run"
    assert first["error"] and second["error"] is None
    assert rec["error"] == first["error"]  # the episode ends as attempt 1 did
    assert got == label, (rec["error"], rec["llm"]["attempts"])
