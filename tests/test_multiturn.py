"""``--interaction multi``: turns of code with execution feedback, end to end through a real HTTP server.

The server (tests/llm_stub_server.py) answers each turn from a script chosen by the turn's number
(the assistant messages already in the conversation); the answers are fixtures, never results.
Everything else is real: prompt files, litellm HTTP, the cache, the sandbox, the planner API,
MuJoCo physics, the cameras, the task predicate, the records and the failure label.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from capmj.agents.llm_agent.agent import LLMAgent
from capmj.agents.llm_agent.multiturn import FINISHED, parse_answer, system_prompt
from capmj.agents.llm_agent.options import LLMAgentOptions
from capmj.agents.prompt_files import object_names
from capmj.bench.failures import classify
from capmj.bench.migrate import as_record
from capmj.errors import ConfigError
from capmj.llm import LLMConfig
from capmj.records import LLMNotes
from capmj.records.notes import TURNS_USED_UP
from capmj.runner import run_episode
from capmj.tasks.registry import get_task
from hostile_plans import HOSTILE_PLANS
from llm_stub_server import Reply, StubLLMServer, prompt_text
from test_llm_chain import MemoryRecorder

TASK = "stack-all-blocks-on-a-zone"
SEED = 10001  # orange zone 1 (target), purple zone 2, blocks 3..7
ZONE = "fixed orange zone with obj_id 1"

LOOK = f"zone = '{ZONE}'\nblocks = [n for n in objects if ' block ' in n]\nprint(len(blocks), 'blocks')\n"
DEFINE = ("def stack_all(names):\n    for n in names:\n        put_first_on_second(n, zone)\n"
          "    return len(is_target_occupied(zone))\n")
CALL = "print('in the zone:', stack_all(blocks))\n"


def code(text: str) -> str:
    return f"```python\n{text.strip()}\n```"


def is_describe(request: dict[str, Any]) -> bool:
    return "The images show a robot's table" in prompt_text(request)


def turn_of(request: dict[str, Any]) -> int:
    """The turn a planner request asks for: 1 + the answers already in its conversation."""
    assert "controls a robot in turns" in prompt_text(request), prompt_text(request)[:200]
    return 1 + sum(m["role"] == "assistant" for m in request["messages"])


def last_user(request: dict[str, Any]) -> Any:
    return request["messages"][-1]["content"]


def last_user_text(request: dict[str, Any]) -> str:
    content = last_user(request)
    return content if isinstance(content, str) else "\n".join(p.get("text", "") for p in content)


def turns(*answers: str | Callable[[dict[str, Any]], str], describe: str = "") -> Callable[[dict[str, Any]], Reply]:
    """A responder answering turn k with ``answers[k - 1]`` (text, or a function of the request)."""

    def respond(request: dict[str, Any]) -> Reply:
        if is_describe(request):
            return Reply.answer(describe)
        k = turn_of(request)
        if k > len(answers):
            raise AssertionError(f"no scripted answer for turn {k}")
        answer = answers[k - 1]
        return Reply.answer(answer(request) if callable(answer) else answer)

    return respond


def agent(server: StubLLMServer, *, llm: dict[str, Any] | None = None, **options: Any) -> LLMAgent:
    config = LLMConfig("openai/stub", api_base=server.base_url, **{"backoff_s": 0.0, "timeout_s": 10.0, **(llm or {})})
    return LLMAgent(config, LLMAgentOptions(interaction="multi", **options))


def episode(a: LLMAgent):
    return run_episode(get_task(TASK), SEED, a)


def roundtrip(notes: LLMNotes) -> None:
    assert LLMNotes.from_dict(notes.to_dict()) == notes


# ------------------------------------------------------------------------------------------------
# the interaction
# ------------------------------------------------------------------------------------------------
def test_three_turns_share_one_namespace_and_finish(server: StubLLMServer) -> None:
    server.respond_with(turns(code(LOOK), code(DEFINE), code(CALL) + "\nFINISH\n"))
    result = episode(agent(server))

    assert result.success and result.error is None, (result.error, result.diagnostics)
    llm = result.llm
    assert [t.attempt for t in llm.attempts] == [1, 2, 3] and all(t.error is None for t in llm.attempts)
    assert [t.finish for t in llm.attempts] == [False, False, True]
    assert [t.rule for t in llm.attempts] == ["next_turn", "next_turn", "finish"]
    assert [t.primitives for t in llm.attempts] == [0, 0, 5] and not any(t.reset for t in llm.attempts)
    assert llm.stopped == FINISHED and llm.finish_agreed is True
    assert (llm.interaction, llm.feedback, llm.max_turns) == ("multi", "text", 8)
    assert "5 blocks" in llm.attempts[0].feedback and f"objects = [{ZONE!r}" in llm.attempts[0].feedback
    assert llm.attempts[2].feedback is None  # nothing is sent after the last turn
    assert llm.calls == 3 and llm.attempts[0].images == 0
    # turn 3's request is the whole conversation: the planner prompt, each answer and its feedback
    third = server.requests[2]["messages"]
    assert [m["role"] for m in third] == ["system", "user", "assistant", "user", "assistant", "user"]
    assert third[0]["content"] == system_prompt(8) and "You have 8 turns" in third[0]["content"]
    assert "Write the plan for the goal in the last comment" in third[1]["content"]
    record = as_record(result)
    assert record.failure is None
    roundtrip(llm)


def test_a_raise_in_turn_1_is_fixed_only_when_the_feedback_names_it(server: StubLLMServer) -> None:
    wrong = f"blocks = [n for n in objects if ' block ' in n]\nput_first_on_second(blocks[7], '{ZONE}')\n"
    # a turn that raised keeps none of its bindings: the fix names the blocks again
    fix = f"blocks = [n for n in objects if ' block ' in n]\nfor n in blocks:\n    put_first_on_second(n, '{ZONE}')\n"

    def second(request: dict[str, Any]) -> str:
        told = last_user_text(request)
        named = "IndexError" in told and "line 2: put_first_on_second(blocks[7]" in told
        return code(fix) if named else code("print('the feedback did not name the exception')")

    server.respond_with(turns(code(wrong), second, "FINISH"))
    result = episode(agent(server))

    assert result.success, (result.error, result.diagnostics)
    first = result.llm.attempts[0]
    assert first.error_type == "IndexError" and first.error_line == 2 and first.failed_program == "planner"
    assert result.llm.attempts[1].error is None and result.llm.attempts[1].primitives == 5
    assert result.llm.stopped == FINISHED and result.llm.finish_agreed is True


def test_a_model_that_never_says_finish_ends_at_max_turns_with_its_own_label(server: StubLLMServer) -> None:
    server.respond_with(lambda request: Reply.answer(code("print('still looking')")))
    result = episode(agent(server, max_turns=3))

    assert not result.success and result.error is None
    llm = result.llm
    assert len(llm.attempts) == 3 and llm.stopped == TURNS_USED_UP and llm.finish_agreed is None
    assert [t.rule for t in llm.attempts] == ["next_turn", "next_turn", "max_turns"]
    assert as_record(result).failure == "no_finish"
    assert classify(as_record(result)) == "no_finish"
    roundtrip(llm)


def test_a_finish_the_predicate_denies_is_recorded_as_disagreement(server: StubLLMServer) -> None:
    server.respond_with(turns("FINISH"))
    result = episode(agent(server))
    assert not result.success and result.llm.finish_agreed is False and len(result.llm.attempts) == 1
    assert as_record(result).failure == "wrong_plan"


@pytest.mark.parametrize("hostile", [p for p in HOSTILE_PLANS if not p.helpers and not p.secret
                                     and p.name in ("format_dynamic_globals", "broadcast_add", "say_aliased_lists",
                                                    "format_literal_globals")],
                         ids=lambda p: p.name)
def test_a_hostile_block_in_turn_2_is_contained_as_in_a_single_plan(server: StubLLMServer, hostile) -> None:
    server.respond_with(lambda request: Reply.answer(code(hostile.code)))
    single = run_episode(get_task(TASK), SEED, LLMAgent(
        LLMConfig("openai/stub", api_base=server.base_url, backoff_s=0.0, timeout_s=10.0)))
    assert single.error_type == hostile.expected

    server.reset()
    server.respond_with(turns(code(LOOK), code(hostile.code), "FINISH"))
    result = episode(agent(server))
    second = result.llm.attempts[1]
    assert second.error_type == single.error_type == hostile.expected
    assert second.error == single.llm.attempts[0].error  # the same words, the same line
    assert result.llm.stopped == FINISHED and len(result.llm.attempts) == 3  # the episode went on
    assert hostile.expected in result.llm.attempts[1].feedback


@pytest.mark.parametrize("feedback", ["text", "image", "describe"])
def test_image_parts_are_sent_only_with_image_or_describe(server: StubLLMServer, feedback: str) -> None:
    server.respond_with(turns(code(LOOK), "FINISH", describe="Nothing moved."))
    result = episode(agent(server, feedback=feedback))
    assert result.llm.stopped == FINISHED, result.llm.attempts

    def images(request: dict[str, Any]) -> int:
        return sum(isinstance(m["content"], list) and sum(p.get("type") == "image_url" for p in m["content"])
                   for m in request["messages"])

    planner = [r for r in server.requests if not is_describe(r)]
    described = [r for r in server.requests if is_describe(r)]
    first = result.llm.attempts[0]
    if feedback == "text":
        assert not described and all(images(r) == 0 for r in planner) and first.images == 0
    elif feedback == "image":
        assert not described and images(planner[0]) == 0 and images(planner[1]) == first.images >= 1
    else:
        assert len(described) == 1 and all(images(r) == 0 for r in planner)
        assert images(described[0]) == first.images >= 2  # the views before and after the turn
        assert first.described == "Nothing moved." and "Nothing moved." in last_user_text(planner[1])
    if feedback != "describe":
        assert first.described is None and "What changed in the camera views" not in first.feedback


def test_a_multi_turn_run_replays_exactly_from_its_cache(server: StubLLMServer, tmp_path: Path) -> None:
    server.respond_with(turns(code(LOOK), code(DEFINE), code(CALL) + "\nFINISH\n"))
    first = episode(agent(server, llm={"cache_dir": tmp_path}))
    assert first.success and len(server.requests) == 3
    server.reset()
    server.respond_with(lambda request: Reply.error(500, "must not be called"))
    again = episode(agent(server, llm={"cache_dir": tmp_path}))
    assert len(server.requests) == 0 and again.llm.cached_calls == again.llm.calls == 3
    same = ("success", "progress", "reward", "primitives", "attempts", "error", "diagnostics", "sim_s")
    assert {k: getattr(again, k) for k in same} == {k: getattr(first, k) for k in same}
    assert [a.to_dict() for a in again.llm.attempts] == [a.to_dict() for a in first.llm.attempts]


# ------------------------------------------------------------------------------------------------
# parts
# ------------------------------------------------------------------------------------------------
def test_answers_are_code_finish_or_both() -> None:
    assert parse_answer("FINISH") == parse_answer("  FINISH \n") and parse_answer("FINISH").finish
    assert parse_answer("FINISH").code is None and parse_answer("FINISH").error is None
    both = parse_answer(code("say('x')") + "\nFINISH")
    assert both.finish and both.code == "say('x')\n"
    assert not parse_answer(code("x = 'FINISH'\nFINISH = 1")).finish  # inside the block it is code
    prose = parse_answer("I think we are done.")
    assert prose.code is None and not prose.finish and type(prose.error).__name__ == "NoCodeError"


def test_multi_takes_its_own_options_and_single_refuses_them() -> None:
    assert LLMAgentOptions().interaction == "single" and LLMAgentOptions().feedback is None
    multi = LLMAgentOptions(interaction="multi")
    assert (multi.feedback, multi.max_turns) == ("text", 8)
    for bad in ({"feedback": "image"}, {"max_turns": 3}, {"describe_model": "openai/m"}):
        with pytest.raises(ConfigError, match="--interaction multi"):
            LLMAgentOptions(**bad)
    for bad in ({"reporter": "text"}, {"attempts": 2}):
        with pytest.raises(ConfigError, match="--interaction multi takes no"):
            LLMAgentOptions(interaction="multi", **bad)
    with pytest.raises(ConfigError, match="max_turns"):
        LLMAgentOptions(interaction="multi", max_turns=0)
    with pytest.raises(ConfigError, match="describe"):
        LLMAgentOptions(interaction="multi", describe_model="openai/m")
    with pytest.raises(ConfigError, match="unknown feedback"):
        LLMAgentOptions(interaction="multi", feedback="video")


def test_the_bench_command_line_passes_the_multi_turn_options() -> None:
    from capmj.bench.cli import build_parser
    from capmj.bench.options import given_agent_options

    args = build_parser().parse_args(["--agent", "llm", "--interaction", "multi", "--feedback", "image",
                                      "--max-turns", "4"])
    assert given_agent_options(args) == {"interaction": "multi", "feedback": "image", "max_turns": 4}


def test_the_documented_command_runs_and_replays_exactly(server: StubLLMServer, tmp_path: Path) -> None:
    """docs/llm.md's multi-turn command, against the scripted server (one task, in this process),
    then ``replay-check`` of its folder from the cache alone."""
    import json

    from capmj.bench.cli import main
    from capmj.bench.replay_check import main as replay_check

    doc = (Path(__file__).resolve().parents[1] / "docs" / "llm.md").read_text()
    section = doc.split("## Multi-turn code with execution feedback")[1].split("\n## ")[0]
    argv = section.split("python -m capmj.bench ")[1].split("```")[0].replace("\\\n", " ").split()
    given = dict(zip(argv[::2], argv[1::2]))
    assert given["--interaction"] == "multi" and given["--feedback"] == "text" and given["--max-turns"] == "8"
    swap = {"--model": "openai/stub", "--api-base": server.base_url, "--llm-cache": str(tmp_path / "cache"),
            "--tasks": TASK, "--out": str(tmp_path / "run"), "--workers": "0"}
    argv = [x for k, v in given.items() for x in (k, swap.get(k, v))]
    server.respond_with(turns(code(LOOK), "FINISH"))
    assert main(argv) == 0
    episodes = [json.loads(line) for line in (tmp_path / "run" / "episodes.jsonl").read_text().splitlines()]
    assert len(episodes) == 2 and all(e["llm"]["interaction"] == "multi" for e in episodes)
    assert all(e["failure"] == "wrong_plan" and e["llm"]["finish_agreed"] is False for e in episodes)
    config = json.loads((tmp_path / "run" / "config.json").read_text())
    assert {k: config["args"]["agent_options"][k] for k in ("interaction", "feedback", "max_turns")} == {
        "interaction": "multi", "feedback": "text", "max_turns": 8}
    assert config["manifest"]["interaction"] == {"mode": "multi", "feedback": "text", "max_turns": 8,
                                                 "describe_model": None}
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    turns_ = summary["overall"]["llm openai/stub"]["loop"]["turns"]
    assert turns_ == {"episodes": 2, "mean_turns": 2.0, "finished": 2, "finish_agree": 0,
                      "finish_false_positives": 2, "finish_agreement": 0.0, "no_finish": 0}
    assert "## Multi-turn (LLM agent, --interaction multi)" in (tmp_path / "run" / "summary.md").read_text()
    server.reset()
    server.respond_with(lambda request: Reply.error(500, "must not be called"))
    assert replay_check([str(tmp_path / "run")]) == 0
    assert len(server.requests) == 0


def test_each_turn_is_logged_as_an_attempt_with_its_feedback_and_views(server: StubLLMServer) -> None:
    server.respond_with(turns(code(LOOK), "FINISH"))
    rec = MemoryRecorder()
    result = run_episode(get_task(TASK), SEED, agent(server, feedback="image"), recorder=rec)
    first = result.llm.attempts[0]
    assert rec.texts["llm/attempt1/feedback"] == [first.feedback]
    assert rec.texts["llm/attempt1/output"] == ["5 blocks"]
    assert rec.texts["llm/attempt2/planner/1/completion"] == ["FINISH"]
    views = [p for p in rec.images if p.startswith("llm/attempt1/feedback/after_")]
    assert len(views) == first.images >= 1


def test_under_rgbd_the_feedback_shows_the_perceived_scene_not_the_truth(server: StubLLMServer) -> None:
    server.respond_with(turns(code(LOOK), "FINISH"))
    result = episode(agent(server, perception="rgbd"))
    assert result.perception is not None
    feedback = result.llm.attempts[0].feedback
    prompt_objects = [line for line in last_user_text({"messages": server.requests[0]["messages"][:2]})
                      .splitlines() if line.startswith("objects = ")][-1]  # the question's, after the examples
    shown_objects = next(line for line in feedback.splitlines() if line.startswith("objects = "))
    assert shown_objects == prompt_objects  # the planner API's view, as in the planner prompt
    shown = dict(line[2:].split(": ", 1) for line in feedback.splitlines() if line.startswith("# ") and ": [" in line)
    assert list(shown) == object_names(shown_objects)
    truth = {name: str([round(float(v), 3) for v in pose[:3]]) for name, pose in result.final_poses.items()}
    assert shown != truth  # the cameras' scene (its names and centres), never the simulator's


def test_describe_model_is_its_own_client_and_its_calls_count(server: StubLLMServer) -> None:
    server.respond_with(turns(code(LOOK), "FINISH", describe="The robot did not move anything."))
    result = episode(agent(server, feedback="describe", describe_model="openai/describer"))
    models = [r.get("model") for r in server.requests]
    assert models == ["stub", "describer", "stub"]
    assert result.llm.calls == 3 and result.llm.attempts[0].llm_calls == 2  # the turn's answer and its description
    assert result.llm.attempts[0].described == "The robot did not move anything."


def test_the_episodes_llm_budget_ends_the_turns(server: StubLLMServer) -> None:
    server.respond_with(lambda request: Reply.answer(code("print('still looking')")))
    result = episode(agent(server, episode_max_tokens=1000))
    assert result.llm.stopped == "llm budget" and result.llm.attempts[-1].rule == "llm_budget"
    assert as_record(result).failure == "budget" and len(result.llm.attempts) < 8
