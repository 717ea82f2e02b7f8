"""One frozen bench configuration: built from the command line, stored in config.json, reloaded by
--resume with the execution settings, a setting given again recorded as a change (issue #28, step 5).

The "model" of the end-to-end tests is the stub server with the scripted task-A planner
(tests/stub_solver.py): a fixture, so the real sandbox, API and physics run while the server sets
the latency that shows how many requests are in flight.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import FrozenInstanceError
from pathlib import Path

import pytest
from llm_stub_server import StubLLMServer
from stub_solver import TASK, solver

from capmj.bench.cli import build_parser, main
from capmj.bench.config import BenchConfig, Given, changes, config_json, effective_args, stored_config
from capmj.bench.executor import Execution
from capmj.bench.options import AGENT_OPTIONS, LABEL_OPTIONS, given_agent_options
from capmj.bench.run import read_command_line

OLD_RUN = Path(__file__).parent / "old_runs" / "cf25f28" / "llm"  # written by the main of commit cf25f28
LATENCY_S = 0.6


def _config(path: Path) -> dict:
    return json.loads((path / "config.json").read_text())


def test_the_configuration_is_frozen_and_read_from_the_command_line_once() -> None:
    argv = ["--agent", "llm", "--model", "openai/m", "--llm-timeout", "600", "--reporter", "text", "--cache-only",
            "--llm-cache", "/tmp/c", "--workers", "1", "--concurrency", "1", "--max-llm-concurrency", "3",
            "--no-log", "--max-tokens", "1000", "--out", "runs/x"]
    inv, given = read_command_line(build_parser().parse_args(argv), argv)
    config = BenchConfig.resolve(given)
    assert config.agent == "llm" and config.execution == Execution(1, 1, 3, "local", None)
    # --reporter text without a loop policy or prompt gets the ones measured never to hurt (#49 item 7)
    assert config.agent_options == {"model": "openai/m", "timeout_s": 600.0, "reporter": "text", "cache_only": True,
                                    "cache_dir": "/tmp/c", "loop_policy": "careful", "reporter_prompt": "relations"}
    assert not config.log and config.run_budget.max_tokens == 1000 and inv.run_dir.root == Path("runs/x")
    with pytest.raises(FrozenInstanceError):
        config.agent = "oracle"  # type: ignore[misc]
    assert BenchConfig.from_args(config.to_args()) == config  # config.json round trip


def test_defaults_depend_on_the_agent_and_nothing_given_stays_a_default() -> None:
    llm = BenchConfig.resolve(Given(agent="llm"))
    assert llm.execution.concurrency == 4 and llm.tasks == "benchmark" and llm.log and not llm.log_images
    assert BenchConfig.resolve(Given()).execution.concurrency == 1 and BenchConfig.resolve(Given()).agent == "oracle"


def test_resume_reloads_every_setting_and_a_given_one_wins() -> None:
    earlier = BenchConfig("A", "1,3", "llm", {"model": "openai/m", "api_base": "http://h/v1", "reporter": "text"},
                          Execution(1, 1, 2), log=False)
    assert BenchConfig.resolve(Given(), earlier) == earlier
    later = BenchConfig.resolve(Given(agent_options={"timeout_s": 900.0}, execution={"concurrency": 2}), earlier)
    assert later.agent_options == dict(earlier.agent_options, timeout_s=900.0)  # the model and server kept
    assert later.execution == Execution(1, 2, 2) and not later.log
    assert changes(earlier.to_args(), later.to_args()) == {
        "agent_options.timeout_s": {"from": None, "to": 900.0}, "concurrency": {"from": 1, "to": 2}}
    other = BenchConfig.resolve(Given(agent="oracle"), earlier)  # another agent: not the llm's options
    assert other.agent_options == {} and other.execution.workers == 1


def test_config_json_keeps_what_the_earlier_parts_ran_with() -> None:
    first = BenchConfig("A", "1", "llm", {"model": "openai/m"}, Execution(1, 1))
    grid = {"tasks": ["A"], "seeds": [1], "agent": "llm", "model": "openai/m", "versions": {}, "manifest": {"m": 1}}
    stored = config_json(first, ["--workers", "1"], grid, None)
    second = BenchConfig.resolve(Given(execution={"workers": 2}), stored_config(stored))
    stored2 = config_json(second, ["--resume", "--workers", "2"], grid, stored)
    third = BenchConfig.resolve(Given(), stored_config(stored2))
    stored3 = config_json(third, ["--resume"], grid | {"manifest": {"m": 2}}, stored2)
    assert stored3["args"] == first.to_args() and stored3["argv"] == ["--workers", "1"]
    assert [r["changed"] for r in stored3["resumes"]] == [{"workers": {"from": 1, "to": 2}}, {}]
    assert [r["argv"] for r in stored3["resumes"]] == [["--resume", "--workers", "2"], ["--resume"]]
    assert third.execution.workers == 2 and effective_args(stored3)["workers"] == 2  # the latest part's
    assert stored3["manifest"] == {"m": 1} and stored3["resumes"][1]["manifest"] == {"m": 2}


def test_option_names_are_defined_once() -> None:
    args = build_parser().parse_args(["--agent", "llm", "--reporter", "vlm", "--llm-max-tokens", "99",
                                      "--replan-retries", "2", "--perception", "rgbd", "--price", "1,2"])
    assert given_agent_options(args) == {"reporter": "vlm", "max_tokens": 99, "replan_retries": 2,
                                         "perception": "rgbd", "price": "1,2"}
    assert set(LABEL_OPTIONS) <= set(AGENT_OPTIONS)
    from dataclasses import fields

    from capmj.agents.llm_agent.options import CONFIG_FIELDS, LLM_AGENT_OPTIONS, LLMAgentOptions
    from capmj.llm import LLMConfig

    assert set(AGENT_OPTIONS) <= set(LLM_AGENT_OPTIONS)  # every option reaches the agent's configuration...
    # ... as a field of one of its two records
    assert set(CONFIG_FIELDS) <= {f.name for f in fields(LLMConfig)}
    assert set(LLM_AGENT_OPTIONS) - set(CONFIG_FIELDS) == {f.name for f in fields(LLMAgentOptions)}


def _llm_grid(server: StubLLMServer, out: Path, *extra: str) -> int:
    return main(["--agent", "llm", "--model", "openai/stub", "--api-base", server.base_url, "--reporter", "none",
                 "--tasks", TASK, "--out", str(out), "--no-progress", "--no-log", *extra])


def test_resume_runs_with_the_stored_workers_and_concurrency(tmp_path: Path, capsys) -> None:
    """The bug of issue #28: a resume of a --workers 1 --concurrency 1 run ran at 2 × 4 in flight and
    rewrote config.json as if the whole run had."""
    out = tmp_path / "run"
    with StubLLMServer() as server:
        server.respond_with(solver(LATENCY_S))
        assert _llm_grid(server, out, "--seeds", "10001", "--workers", "1", "--concurrency", "1") == 0
        capsys.readouterr()
        first = len(server.request_log)
        # the grid grows by three seeds; nothing says how to run them
        assert main(["--out", str(out), "--resume", "--seeds", "10001:10009:2", "--no-progress"]) == 0
        starts = sorted(r.received_at for r in server.request_log[first:])
    assert "3 to run on 1 worker(s) × 1 in flight" in capsys.readouterr().err
    assert len(starts) == 3 and all(b - a >= LATENCY_S - 0.05 for a, b in zip(starts, starts[1:])), starts
    lines = (out / "episodes.jsonl").read_text().splitlines()
    assert sorted(json.loads(x)["seed"] for x in lines) == [10001, 10003, 10005, 10007]
    cfg = _config(out)
    assert (cfg["args"]["workers"], cfg["args"]["concurrency"], cfg["args"]["seeds"]) == (1, 1, "10001")
    assert cfg["resumes"][-1]["changed"] == {"seeds": {"from": "10001", "to": "10001:10009:2"}}
    # given again: recorded as a change, the first part's settings untouched; nothing left to run
    assert main(["--out", str(out), "--resume", "--workers", "0", "--no-progress"]) == 0
    cfg = _config(out)
    assert cfg["args"]["workers"] == 1 and cfg["resumes"][-1]["changed"] == {"workers": {"from": 1, "to": 0}}
    assert "0 to run on 0 worker(s) × 1 in flight" in capsys.readouterr().err


def test_a_config_json_from_before_resumes_with_its_settings(tmp_path: Path, capsys) -> None:
    out = tmp_path / "old"
    shutil.copytree(OLD_RUN, out)
    old = _config(out)
    assert "resumes" not in old and old["args"]["workers"] == 0
    assert main(["--out", str(out), "--resume", "--no-progress"]) == 0  # complete: no request is sent
    assert "0 to run on 0 worker(s) × 1 in flight" in capsys.readouterr().err
    cfg = _config(out)
    assert cfg["args"] == old["args"] and cfg["argv"] == old["argv"] and cfg["started_at"] == old["started_at"]
    assert cfg["resumes"][-1]["changed"] == {} and cfg["resumes"][-1]["argv"][-1] == "--no-progress"
    assert stored_config(cfg).agent_options == old["args"]["agent_options"]


def test_the_report_of_a_run_folder_labels_it_with_its_agent_options(tmp_path: Path, capsys) -> None:
    """The options are read from where config.json keeps them (``args.agent_options``, with each
    resume's changes applied), not from the top level, where they never were."""
    out = tmp_path / "run"
    with StubLLMServer() as server:
        server.respond_with(solver())
        assert _llm_grid(server, out, "--seeds", "10001", "--workers", "0", "--attempts", "2") == 0
        assert main(["--out", str(out), "--resume", "--temperature", "0.3", "--no-progress"]) == 0
    capsys.readouterr()
    assert main(["report", str(out), "--out", str(tmp_path / "rep")]) == 0
    md = capsys.readouterr().out
    label = "llm openai/stub (reporter=none, attempts=2, temperature=0.3)"
    header = next(line for line in md.splitlines() if line.startswith("| Task |"))
    assert f"{label} (n=1)" in header, header
    assert list(json.loads((tmp_path / "rep" / "summary.json").read_text())["overall"]) == [label]
