"""What a real model's output exposed (issue 10), each slip as a scripted completion.

Every completion here is a fixture served by the local OpenAI-compatible HTTP server
(tests/llm_stub_server.py); everything else is real: litellm HTTP, the cache, the sandbox, the
planner API, MuJoCo physics.  Scene: stack-all-blocks-on-a-zone, seed 10001 (orange zone 1,
purple zone 2, small blocks cyan 3, yellow 4, pink 5, red 6, blue 7).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

from llm_stub_server import Reply, StubLLMServer
from test_llm_chain import OBJ_NAMES, MemoryRecorder, Router, agent, code, episode

ZONE = "fixed orange zone with obj_id 1"
CYAN, YELLOW, PINK = ("movable small cyan block with obj_id 3", "movable small yellow block with obj_id 4",
                      "movable small pink block with obj_id 5")
REPO = Path(__file__).resolve().parents[1]


def plan_only(server: StubLLMServer, plan: str, **handlers: Any) -> Router:
    router = Router(planner=code(plan), **handlers)
    server.respond_with(router)
    return router


# ------------------------------------------------------------------------------------------------
# 1. deterministic budgets
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("plan", ["while True: pass", "while True:\n    x = np.zeros(10**6)"])
def test_endless_plan_ends_its_attempt_with_a_named_budget(server: StubLLMServer, plan: str) -> None:
    plan_only(server, "say('start')\n" + plan)
    result = episode(agent(server))  # the default plan budget, no wall-time override
    assert result.error is not None and result.error.startswith("BudgetExceeded: line "), result.error
    assert " of the plan: `" in result.error
    budget = "executed-line budget of 100000 lines" if "pass" in plan else "allocation budget of"
    assert budget in result.error, result.error
    assert "`while True" in result.error or "`x = np.zeros" in result.error  # the line is quoted


ENDLESS = textwrap.dedent("""
    import json, sys
    from capmj.agents.sandbox import SandboxBudget, run_code
    from capmj.errors import BudgetExceeded
    out = []
    for code in ["while True: pass", "i = 0\\nwhile True:\\n    i += 1",
                 "while True:\\n    x = np.zeros(10**5)", "s = [c for c in set('abcdef')]\\nwhile True:\\n    s = s[1:] + s[:1]"]:
        try:
            run_code(code, {}, budget=SandboxBudget(wall_s=120, max_lines=50_000), program="the plan")
        except BudgetExceeded as exc:
            out.append(str(exc))
    print(json.dumps(out))
""")


def test_endless_variants_stop_at_the_same_line_count_in_two_processes() -> None:
    runs = []
    for hash_seed in ("1", "2"):
        env = dict(os.environ, PYTHONHASHSEED=hash_seed)
        proc = subprocess.run([sys.executable, "-c", ENDLESS], env=env, capture_output=True, text=True,
                              timeout=300, check=True)
        runs.append(json.loads(proc.stdout))
    assert len(runs[0]) == 4 and runs[0] == runs[1]
    assert all("executed lines" in m for m in runs[0]), runs[0]


# ------------------------------------------------------------------------------------------------
# 2. exact replays
# ------------------------------------------------------------------------------------------------
SET_PLAN = f"""
names = [{CYAN!r}, {YELLOW!r}]
for name in set(names):
    put_first_on_second(name, {ZONE!r})
say(str(list({{n for n in names}})))
"""
WORKER = textwrap.dedent("""
    import json, sys
    from capmj.agents.llm_agent.agent import LLMAgent
    from capmj.llm import LLMConfig
    from capmj.runner import run_episode
    from capmj.tasks.registry import get_task
    agent = LLMAgent(LLMConfig("openai/stub", api_base=sys.argv[1], backoff_s=0.0, timeout_s=30.0))
    result = run_episode(get_task("stack-all-blocks-on-a-zone"), 10001, agent)
    print(json.dumps({"error": result.error, "said": list(result.llm.attempts[0].said),
                      "primitives": result.primitives, "progress": result.progress, "sim_s": result.sim_s}))
""")


def _plain_set_order(names: list[str], hash_seed: str | None) -> list[str]:
    if hash_seed is None:
        return list(set(names))
    probe = f"import json, sys; print(json.dumps(list(set({names!r}))))"
    env = dict(os.environ, PYTHONHASHSEED=hash_seed)
    return json.loads(subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True,
                                     check=True).stdout)


def test_a_plan_iterating_a_set_gives_the_same_final_state_in_two_processes(server: StubLLMServer) -> None:
    """This process and a worker whose string hashing orders the plan's names differently."""
    names = [CYAN, YELLOW]
    here = _plain_set_order(names, None)
    hash_seed = next(h for h in map(str, range(1, 50)) if _plain_set_order(names, h) != here)
    server.respond_with(Router(planner=code(SET_PLAN)))
    proc = subprocess.run([sys.executable, "-c", WORKER, server.base_url], capture_output=True, text=True,
                          env=dict(os.environ, PYTHONHASHSEED=hash_seed), timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    worker = json.loads(proc.stdout.strip().splitlines()[-1])
    result = episode(agent(server))
    local = {"error": result.error, "said": list(result.llm.attempts[0].said), "primitives": result.primitives,
             "progress": result.progress, "sim_s": result.sim_s}
    # sets in LLM code iterate in insertion order, so the same tower is built in both processes
    assert local == worker
    assert local["error"] is None and local["primitives"] == 2 and local["said"] == [str(names)]


RANDOM_PLAN = f"""
x = np.random.uniform(0.4, 0.6)
y = float(np.random.choice([-0.25, -0.2, 0.2, 0.25]))
order = np.random.permutation(3).tolist()
put_first_on_second({CYAN!r}, [x, y])
say(f'{{x:.9f}} {{y}} {{order}}')
"""


def test_np_random_replays_identically_from_the_cache(server: StubLLMServer, tmp_path: Path) -> None:
    plan_only(server, RANDOM_PLAN)
    rec1 = MemoryRecorder()
    first = episode(agent(server, llm={"cache_dir": tmp_path}), rec1)
    assert first.error is None and first.primitives == 1
    said = first.llm.attempts[0].said
    assert len(server.requests) == 1
    server.reset()
    server.respond_with(lambda request: Reply.error(500, "must not be called"))
    rec2 = MemoryRecorder()
    again = episode(agent(server, llm={"cache_dir": tmp_path, "cache_only": True}), rec2)
    assert len(server.requests) == 0 and again.llm.cached_calls == 1
    assert again.llm.attempts[0].said == said
    assert rec2.texts["llm/attempt1/api_calls"] == rec1.texts["llm/attempt1/api_calls"]
    assert (again.success, again.progress, again.sim_s) == (first.success, first.progress, first.sim_s)


def test_cache_only_with_a_missing_entry_fails_the_episode_without_http(server: StubLLMServer,
                                                                         tmp_path: Path) -> None:
    plan = "blocks = parse_obj_name('the blocks')\nsay(str(len(blocks)))"
    plan_only(server, plan, parse_obj_name=code(OBJ_NAMES))
    first = episode(agent(server, llm={"cache_dir": tmp_path}))
    assert first.error is None and first.llm.attempts[0].said == ("5",)
    entries = sorted(tmp_path.rglob("*.json"))
    assert len(entries) == 2
    (helper,) = [p for p in entries if "ret_val" in json.loads(p.read_text())["text"]]
    helper.unlink()  # the parse_obj_name completion is gone
    server.reset()
    server.respond_with(lambda request: Reply.error(500, "must not be called"))
    again = episode(agent(server, attempts=2, llm={"cache_dir": tmp_path, "cache_only": True}))
    assert len(server.requests) == 0
    assert again.error is not None and again.error.startswith("LLMError: cache-only: no cached completion "
                                                               "for parse_obj_name#1"), again.error
    assert again.llm.stopped == "llm error" and len(again.llm.attempts) == 1


# ------------------------------------------------------------------------------------------------
# 3. names owned by the API, the LMPs or the episode are never synthesised
# ------------------------------------------------------------------------------------------------
def test_reserved_names_in_the_plan_are_errors_not_synthesised(server: StubLLMServer) -> None:
    router = plan_only(server, "say('x')\ntabletop_ui('do it')\nput_first_on_second(1, 2)")
    result = episode(agent(server))
    assert result.error is not None and "parse_function" not in router.seen
    assert ("line 2 of the plan: `tabletop_ui('do it')`: NameError: tabletop_ui() cannot be called in the plan"
            in result.error)
    assert "it is the planner itself" in result.error and "put_first_on_second" in result.error
    assert result.primitives == 0


def test_a_helper_calling_a_robot_action_gets_an_error_naming_who_may(server: StubLLMServer) -> None:
    helper = code(f"put_first_on_second({CYAN!r}, {ZONE!r})\nret_val = []")
    router = plan_only(server, "blocks = parse_obj_name('the blocks')", parse_obj_name=helper)
    result = episode(agent(server))
    assert router.seen == ["planner", "parse_obj_name"], router.seen
    assert "in the code parse_obj_name wrote for this line, line 1" in result.error
    assert "only the plan may move the robot" in result.error and result.primitives == 0


def test_parse_function_cannot_redefine_the_api(server: StubLLMServer) -> None:
    written = code("def get_obj_pos(obj):\n    return [0, 0, 0]\n\ndef lift(obj):\n    return get_obj_pos(obj)")
    plan_only(server, f"say(str(lift({CYAN!r})[2] > 0.0))", parse_function=written)
    result = episode(agent(server))
    assert result.error is None and result.llm.attempts[0].said == ("True",)  # the real get_obj_pos


def test_wrong_call_of_an_api_function_shows_how_to_call_it(server: StubLLMServer) -> None:
    plan_only(server, f"put_first_on_second({CYAN!r})")
    result = episode(agent(server))
    assert "missing a required argument: 'target'; call it as put_first_on_second(obj, target)" in result.error


# ------------------------------------------------------------------------------------------------
# 4. ordinary code accepted
# ------------------------------------------------------------------------------------------------
def test_type_checks_np_random_and_star_imports_are_accepted(server: StubLLMServer) -> None:
    plan = """from shapely.geometry import *
import numpy as np
names = get_obj_names()
kinds = [type(names) == list, type(get_obj_pos(names[0])) == list, type(1.0) is float]
pick = np.random.choice([n for n in names if 'block' in n])
say(str(all(kinds) and isinstance(Point(0, 0), Point) and pick in names))
"""
    plan_only(server, plan)
    rec = MemoryRecorder()
    result = episode(agent(server), rec)
    assert result.error is None and result.llm.attempts[0].said == ("True",)
    assert "from shapely.geometry import *" in rec.texts["llm/attempt1/planner/1/removed_imports"][0]


# ------------------------------------------------------------------------------------------------
# 5. near-miss object names
# ------------------------------------------------------------------------------------------------
def test_near_miss_names_resolve_when_one_object_fits(server: StubLLMServer) -> None:
    plan = """
put_first_on_second('yellow block with obj_id 4', 'orange zone')
put_first_on_second('movable_cyan_block_with_obj_id_3', 'movable small yellow block with obj_id 4')
"""
    plan_only(server, plan)
    rec = MemoryRecorder()
    result = episode(agent(server), rec)
    assert result.error is None and result.primitives == 2
    log = rec.texts["llm/attempt1/api_calls"][0]
    assert f"'yellow block with obj_id 4' -> {YELLOW!r}" in log and f"'orange zone' -> {ZONE!r}" in log
    assert f"'movable_cyan_block_with_obj_id_3' -> {CYAN!r}" in log


@pytest.mark.parametrize(("name", "closest"), [("zone", ["fixed orange zone", "fixed purple zone"]),
                                               ("yellow block with obj_id 3", [YELLOW, CYAN]),
                                               ("green block", ["movable small"])])
def test_ambiguous_or_wrong_names_list_the_closest(server: StubLLMServer, name: str, closest: list[str]) -> None:
    plan_only(server, f"p = get_obj_pos({name!r})")
    result = episode(agent(server))
    assert f"unknown object {name!r}; closest names: '" in result.error, result.error
    listed = result.error.split("closest names: ")[1].split(". Valid names")[0]
    assert all(c in listed for c in closest), listed


# ------------------------------------------------------------------------------------------------
# 6. errors say which program failed
# ------------------------------------------------------------------------------------------------
def test_a_helper_error_names_the_helper_and_quotes_both_lines(server: StubLLMServer) -> None:
    plan = "x = 1\nbowls = parse_obj_name('the bowls')\n"
    plan_only(server, plan, parse_obj_name=code("ret_val = [bowl_y]"))
    result = episode(agent(server))
    assert result.error == (
        "PlanError: line 2 of the plan: `bowls = parse_obj_name('the bowls')`: in the code parse_obj_name "
        "wrote for this line, line 1: `ret_val = [bowl_y]`: NameError: name 'bowl_y' is not defined")


def test_an_error_inside_a_written_function_names_it(server: StubLLMServer) -> None:
    plan_only(server, "z = lift(3)", parse_function=code("def lift(obj):\n    return 1 / 0"))
    result = episode(agent(server))
    assert "of the plan (in lift(), written by parse_function): `return 1 / 0`: ZeroDivisionError" in result.error


# ------------------------------------------------------------------------------------------------
# 7. CLI
# ------------------------------------------------------------------------------------------------
def test_llm_cli_flags_and_the_large_grid_question(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    from capmj.bench.cli import build_parser, main

    args = build_parser().parse_args(["--agent", "llm", "--llm-timeout", "900", "--llm-cache", "c", "--cache-only"])
    assert (args.timeout_s, args.cache_dir, args.cache_only) == (900.0, "c", True)
    assert main(["--agent", "llm", "--model", "openai/x", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "this would start 500 LLM episodes" in err and "--seeds" in err and "--yes" in err
    assert not (tmp_path / "r").exists()


def test_the_documented_local_llm_command_parses() -> None:
    from capmj.agents.factory import make_agent
    from capmj.bench.cli import build_parser
    from capmj.bench.options import given_agent_options

    doc = (REPO / "docs" / "llm.md").read_text()
    section = doc.split("## Local model (llama.cpp)")[1].split("\n## ")[0]
    command = section.split("python -m capmj.bench ")[1].split("```")[0]
    argv = command.replace("\\\n", " ").split()
    args = build_parser().parse_args(argv)
    assert args.model == "openai/qwen2.5-coder-1.5b" and args.api_base == "http://127.0.0.1:8080/v1"
    options = given_agent_options(args)
    a = make_agent("llm", **options)
    assert a.config.timeout_s >= 300 and a.config.api_base == "http://127.0.0.1:8080/v1"


# ------------------------------------------------------------------------------------------------
# pure units (no server)
# ------------------------------------------------------------------------------------------------
def test_near_miss_rules() -> None:
    from types import SimpleNamespace

    from capmj.agents.api.names import near_miss

    names = ["fixed red zone with obj_id 1", "movable small blue block with obj_id 2",
             "movable big blue block with obj_id 3", "movable small yellow block with obj_id 4",
             "fixed brown bowl with obj_id 5"]
    objs = [SimpleNamespace(name=n, obj_id=i) for i, n in enumerate(names, 1)]

    def fit(query: str) -> str | None:
        o = near_miss(query, objs)  # type: ignore[arg-type]
        return o.name if o is not None else None

    assert fit("yellow block with obj_id 4") == names[3]
    assert fit("movable_blue_block_with_obj_id_3") == names[2]
    assert fit("brown bowl") == fit("the Brown Bowl") == names[4]
    assert fit("big blue block") == names[2]
    for ambiguous_or_wrong in ("blue block", "yellow block with obj_id 3", "movable small red block with obj_id 33",
                               "green block", "block 2 4", "the", ""):
        assert fit(ambiguous_or_wrong) is None, ambiguous_or_wrong


def test_cache_only_needs_a_cache_folder() -> None:
    from capmj.errors import ConfigError
    from capmj.llm import LLMConfig

    with pytest.raises(ConfigError, match="cache_only needs cache_dir"):
        LLMConfig("openai/x", cache_only=True)
