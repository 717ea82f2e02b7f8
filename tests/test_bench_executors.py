"""The bench's executor layer: the run-folder layout, the spawn pool, the shared worker, and an
import graph of ``capmj.bench`` without cycles (issue #28, step 4)."""

from __future__ import annotations

import ast
import os
import signal
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

import pytest

import capmj.bench
from capmj.bench.executor import Execution, describe_exit_codes
from capmj.bench.pool import SpawnPool, spawn_pool
from capmj.bench.rundir import RunDir
from capmj.bench.worker import AgentSpec, Job, Worker
from capmj.errors import ConfigError


def test_run_dir_names_every_file_of_the_folder(tmp_path: Path) -> None:
    run = RunDir(tmp_path / "run")
    assert run.episodes == tmp_path / "run" / "episodes.jsonl" and run.config.name == "config.json"
    assert {run.summary_json.name, run.summary_md.name, run.summary_png.name} == {"summary.json", "summary.md",
                                                                                 "summary.png"}
    # the names earlier runs wrote (records hold them, so they must not change)
    assert RunDir.rrd_relpath("stack-all-blocks-on-a-zone", 10001, "oracle", None) == \
        "rrd/stack-all-blocks-on-a-zone/10001-oracle.rrd"
    assert RunDir.transcript_relpath("a task", 7, "llm", "openai/qwen2.5:7b") == "transcripts/a_task/7-llm-openai_qwen2.5_7b.jsonl"
    assert run.rrd("t", 1, "llm", "m").is_absolute()
    assert run.relative(str(run.rrd("t", 1, "llm", "m"))) == "rrd/t/1-llm-m.rrd"
    assert run.path("rrd/t/1-oracle.rrd") == run.root / "rrd/t/1-oracle.rrd"
    assert run.path("/elsewhere/x.rrd") == Path("/elsewhere/x.rrd")


def test_spawn_pool_spawns_and_names_the_exit_code_of_a_killed_worker() -> None:
    with spawn_pool(1) as pool:
        assert isinstance(pool, SpawnPool) and pool.context.get_start_method() == "spawn"
        pid = pool.submit(os.getpid).result(timeout=120)
        assert pid != os.getpid() and [p.pid for p in pool.processes()] == [pid]
        with pytest.raises(BrokenProcessPool):
            pool.submit(os.kill, pid, signal.SIGKILL).result(timeout=120)
        assert pool.exit_codes() == [-signal.SIGKILL]
        assert describe_exit_codes(pool.exit_codes()) == " (killed by SIGKILL)"
        pool.kill()


def test_a_worker_turns_every_failure_into_its_episode_record() -> None:
    bad_task = Worker(AgentSpec("oracle")).run_job(Job("no-such-task", 1))
    assert bad_task["success"] is False and bad_task["task"] == "no-such-task" and bad_task["error_type"]
    bad_agent = Worker(AgentSpec("no-such-agent"))  # built once; each episode then reports why
    recs = [bad_agent.run_job(Job("stack-all-blocks-on-a-zone", s)) for s in (1, 3)]
    assert [r["seed"] for r in recs] == [1, 3]
    assert all(not r["success"] and r["error_type"] == "ConfigError" and "no-such-agent" in r["error"] for r in recs)


@pytest.mark.parametrize("kwargs, needle", [
    ({"workers": -1}, "--workers"), ({"workers": 1, "concurrency": 0}, "--concurrency"),
    ({"workers": 1, "max_llm_concurrency": 0}, "--max-llm-concurrency"),
    ({"workers": 0, "executor": "ray"}, "--executor ray"), ({"workers": 1, "executor": "slurm"}, "executor"),
])
def test_execution_rejects_what_cannot_run(kwargs: dict, needle: str) -> None:
    with pytest.raises(ConfigError, match=needle):
        Execution(**kwargs)


def _imports(path: Path, package: str) -> set[str]:
    """Modules of ``package`` imported anywhere in ``path`` (at module level or in a function)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else (
            [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            if isinstance(node, ast.ImportFrom) and node.module else [])
        found |= {n for n in names if n.startswith(package + ".")}
    return found


def test_the_bench_package_has_no_import_cycle() -> None:
    root = Path(capmj.bench.__file__).parent
    modules = {f"capmj.bench.{p.stem}": p for p in root.glob("*.py") if p.stem != "__init__"}
    graph = {m: _imports(p, "capmj.bench") & set(modules) - {m} for m, p in modules.items()}
    assert graph["capmj.bench.grid"] and graph["capmj.bench.ray_executor"]  # the graph is really read

    def reaches(start: str, goal: str, seen: set[str]) -> bool:
        for nxt in graph[start]:
            if nxt == goal or (nxt not in seen and reaches(nxt, goal, seen | {nxt})):
                return True
        return False

    assert [m for m in graph if reaches(m, m, {m})] == []
