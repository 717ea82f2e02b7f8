"""``--policy tools``: the planner API as function calls, end to end through a real HTTP server.

The server (tests/llm_stub_server.py) streams its calls in OpenAI's delta format and builds their
arguments from the ``tools`` the request offered (their JSON Schemas' parameter names), so a call
exists only if the client sent the schemas; the answers are fixtures, never results.  Everything
else is real: the generated schemas, litellm HTTP, the cache, the planner API, MuJoCo physics, the
task predicate, the records and the failure labels.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from capmj.agents.api.plan_functions import PlanFunctions
from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.api.tool_schemas import TOOL_FUNCTIONS, json_schema, tool_schemas
from capmj.agents.llm_agent.agent import LLMAgent
from capmj.agents.llm_agent.multiturn import FINISHED
from capmj.agents.llm_agent.options import LLMAgentOptions
from capmj.agents.llm_agent.tools import system_prompt
from capmj.agents.llm_agent.tools_calls import Call, content_calls, run_call
from capmj.agents.prompt_files import load_prompt, object_names, prompts_dir
from capmj.bench.failures import classify
from capmj.bench.migrate import as_record
from capmj.errors import ConfigError, ToolCallingUnsupported
from capmj.llm import LLMConfig
from capmj.records import LLMNotes
from capmj.records.notes import ANSWERED, TURNS_USED_UP
from capmj.runner import run_episode
from capmj.tasks.registry import get_task
from llm_stub_server import Reply, StubLLMServer, offered_tools
from prompt_examples import build_context

TASK = "stack-all-blocks-on-a-zone"
SEED = 10001  # orange zone 1 (target), purple zone 2, blocks 3..7
ZONE = "fixed orange zone with obj_id 1"


def turn_of(request: dict[str, Any]) -> int:
    """The turn a request asks for: 1 + the answers already in its conversation."""
    assert "controls a robot by calling functions" in request["messages"][0]["content"]
    return 1 + sum(m["role"] == "assistant" for m in request["messages"])


def blocks_of(request: dict[str, Any]) -> list[str]:
    names = object_names(request["messages"][1]["content"]) or []
    return [n for n in names if " block " in n]


def put(request: dict[str, Any], obj: str, target: str) -> tuple[str, dict[str, Any]]:
    """A put_first_on_second call whose argument names are the offered schema's, in its order."""
    params = offered_tools(request)["put_first_on_second"]
    first, second = params["required"]
    assert list(params["properties"]) == [first, second]
    return "put_first_on_second", {first: obj, second: target}


def stack_all(request: dict[str, Any]) -> Reply:
    return Reply.calls(*(put(request, b, ZONE) for b in blocks_of(request)))


def turns(*answers: Callable[[dict[str, Any]], Reply] | str) -> Callable[[dict[str, Any]], Reply]:
    def respond(request: dict[str, Any]) -> Reply:
        k = turn_of(request)
        if k > len(answers):
            raise AssertionError(f"no scripted answer for turn {k}")
        answer = answers[k - 1]
        return answer(request) if callable(answer) else Reply.answer(answer)

    return respond


def agent(server: StubLLMServer, *, llm: dict[str, Any] | None = None, **options: Any) -> LLMAgent:
    config = LLMConfig("openai/stub", api_base=server.base_url, **{"backoff_s": 0.0, "timeout_s": 10.0, **(llm or {})})
    return LLMAgent(config, LLMAgentOptions(policy="tools", **options))


def episode(a: LLMAgent):
    return run_episode(get_task(TASK), SEED, a)


def tool_messages(request: dict[str, Any]) -> list[dict[str, Any]]:
    return [m for m in request["messages"] if m["role"] == "tool"]


# ------------------------------------------------------------------------------------------------
# the episode
# ------------------------------------------------------------------------------------------------
def test_calls_built_from_the_offered_schemas_run_in_order_and_reach_the_goal(server: StubLLMServer) -> None:
    server.respond_with(turns(stack_all, "FINISH"))
    result = episode(agent(server))

    assert result.success and result.error is None, (result.error, result.diagnostics)
    llm = result.llm
    assert server.requests[0]["tools"] == tool_schemas()  # the generated schemas, as sent
    first = llm.attempts[0]
    blocks = blocks_of(server.requests[0])
    assert [json.loads(c.arguments)["obj"] for c in first.tool_calls] == blocks  # in the order written
    assert all(c.form == "tool_calls" and c.result == "null" and c.error is None for c in first.tool_calls)
    assert first.primitives == len(blocks) == 5 and first.api_calls == 5
    assert [t.rule for t in llm.attempts] == ["next_turn", "finish"] and llm.attempts[1].tool_calls == ()
    assert (llm.policy, llm.stopped, llm.finish_agreed, llm.max_turns, llm.interaction) == (
        "tools", FINISHED, True, 8, None)
    # turn 2's request: the answer's calls and one tool message per call, answering its id
    second = server.requests[1]["messages"]
    assert [m["role"] for m in second] == ["system", "user", "assistant"] + ["tool"] * 5
    ids = [c["id"] for c in second[2]["tool_calls"]]
    assert ids == [c.id for c in first.tool_calls] and [m["tool_call_id"] for m in second[3:]] == ids
    assert second[0]["content"] == system_prompt(8)
    assert as_record(result).failure is None
    assert LLMNotes.from_dict(llm.to_dict()) == llm
    assert [c["id"] for c in result.calls[0]["tool_calls"]] == ids  # the call log keeps them for the transcripts


def test_an_error_goes_back_as_the_tool_message_and_the_fix_follows(server: StubLLMServer) -> None:
    def wrong(request: dict[str, Any]) -> Reply:
        return Reply.calls(put(request, blocks_of(request)[0], "fixed teal zone with obj_id 99"),
                           ("get_color", {"obj": ZONE}))

    def second(request: dict[str, Any]) -> Reply:
        told = tool_messages(request)
        assert [m["content"] for m in told][1] == '"orange"'  # the second call ran after the first failed
        return stack_all(request) if "error: " in told[0]["content"] and "99" in told[0]["content"] \
            else Reply.answer("the error was not shown")

    server.respond_with(turns(wrong, second, "FINISH"))
    result = episode(agent(server))
    assert result.success, (result.error, result.llm.attempts)
    failed = result.llm.attempts[0].tool_calls[0]
    assert failed.result is None and failed.error is not None and "99" in failed.error
    assert result.llm.attempts[0].primitives == 0 and result.llm.attempts[1].primitives == 5


def test_a_call_written_as_json_in_the_text_is_read_and_labelled(server: StubLLMServer) -> None:
    def in_text(request: dict[str, Any]) -> Reply:
        lines = [json.dumps({"name": name, "arguments": args}) for name, args in
                 (put(request, b, ZONE) for b in blocks_of(request))]
        return Reply.answer("I will stack them.\n<tool_call>\n" + "\n".join(lines) + "\n</tool_call>")

    server.respond_with(turns(in_text, "All blocks are in the orange zone."))
    result = episode(agent(server))
    assert result.success, (result.error, result.llm.attempts)
    calls = result.llm.attempts[0].tool_calls
    assert [c.form for c in calls] == ["content_json"] * 5 and [c.id for c in calls][:2] == ["json_1_1", "json_1_2"]
    sent = server.requests[1]["messages"]
    assert [c["id"] for c in sent[2]["tool_calls"]] == [c.id for c in calls]  # answered as tool messages
    assert result.llm.stopped == ANSWERED and result.llm.attempts[1].rule == "answered"
    assert result.llm.finish_agreed is True


def test_a_model_that_never_stops_calling_ends_at_max_turns_labelled(server: StubLLMServer) -> None:
    server.respond_with(lambda request: Reply.calls(("get_obj_names", {})))
    result = episode(agent(server, max_turns=3))
    assert not result.success and result.error is None
    llm = result.llm
    assert len(llm.attempts) == 3 and llm.stopped == TURNS_USED_UP and llm.finish_agreed is None
    assert [t.rule for t in llm.attempts] == ["next_turn", "next_turn", "max_turns"]
    assert json.loads(llm.attempts[0].tool_calls[0].result)[0] == ZONE
    assert classify(as_record(result)) == "no_finish"


def test_the_episodes_llm_budget_ends_the_turns(server: StubLLMServer) -> None:
    server.respond_with(lambda request: Reply.calls(("get_obj_names", {})))
    result = episode(agent(server, episode_max_tokens=2000))
    assert result.llm.stopped == "llm budget" and result.llm.attempts[-1].rule == "llm_budget"
    assert as_record(result).failure == "budget" and 1 < len(result.llm.attempts) < 8


def test_multi_sends_the_feedback_after_the_tool_messages(server: StubLLMServer) -> None:
    server.respond_with(turns(lambda r: Reply.calls(("get_obj_names", {})), "FINISH"))
    result = episode(agent(server, interaction="multi"))
    last = server.requests[1]["messages"]
    assert [m["role"] for m in last[-3:]] == ["assistant", "tool", "user"]
    assert "After turn 1 (7 turns left)" in last[-1]["content"] and f"# {ZONE}: [" in last[-1]["content"]
    assert result.llm.attempts[0].feedback == last[-1]["content"] and result.llm.interaction == "multi"


def test_a_model_without_tool_calling_fails_at_start_up_naming_it(server: StubLLMServer, tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    from capmj.bench.cli import main

    with pytest.raises(ToolCallingUnsupported, match="gpt-3.5-turbo-instruct"):
        LLMAgent(LLMConfig("gpt-3.5-turbo-instruct"), LLMAgentOptions(policy="tools"))
    LLMAgent(LLMConfig("gpt-3.5-turbo-instruct"))  # the code policy takes it
    with pytest.raises(ToolCallingUnsupported, match="'deepseek-reasoner' has none .*no tool calling"):
        LLMAgent(LLMConfig("deepseek-reasoner"), LLMAgentOptions(policy="tools"))
    LLMAgent(LLMConfig("ollama/qwen2.5-coder"), LLMAgentOptions(policy="tools"))  # listed, tool calling not stated
    # the bench stops before any episode or request
    assert main(["--agent", "llm", "--model", "gpt-3.5-turbo-instruct", "--policy", "tools", "--tasks", TASK,
                 "--seeds", str(SEED), "--out", str(tmp_path / "run"), "--workers", "0", "--no-probe"]) == 2
    assert "'gpt-3.5-turbo-instruct' has none" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
    # a server that refuses the tools: the episode's provider failure names the model
    server.script(Reply.error(400, "tools param requires --jinja flag"))
    result = episode(agent(server))
    assert result.error_type == "ToolsRejected" and "openai/stub" in result.error and "tools" in result.error
    assert result.llm.stopped == "llm error" and len(server.requests) == 1


def test_a_tool_run_replays_exactly_from_its_cache(server: StubLLMServer, tmp_path: Path) -> None:
    server.respond_with(turns(lambda r: Reply.calls(("get_obj_names", {}), text="Looking."), stack_all, "FINISH"))
    first = episode(agent(server, llm={"cache_dir": tmp_path}))
    assert first.success and len(server.requests) == 3
    server.reset()
    server.respond_with(lambda request: Reply.error(500, "must not be called"))
    again = episode(agent(server, llm={"cache_dir": tmp_path}))
    assert len(server.requests) == 0 and again.llm.cached_calls == again.llm.calls == 3
    same = ("success", "progress", "reward", "primitives", "attempts", "error", "diagnostics", "sim_s", "final_poses")
    assert {k: getattr(again, k) for k in same} == {k: getattr(first, k) for k in same}
    assert [a.to_dict() for a in again.llm.attempts] == [a.to_dict() for a in first.llm.attempts]


# ------------------------------------------------------------------------------------------------
# the schemas, the prompt, the parts
# ------------------------------------------------------------------------------------------------
def test_every_function_the_planner_prompt_documents_has_a_schema_and_vice_versa() -> None:
    head = (prompts_dir() / "planner.py").read_text().split("from env_utils import ", 1)[1].split("\n", 1)[0]
    documented = [n.strip() for n in head.split(",")]
    schemas = tool_schemas()
    assert [t["function"]["name"] for t in schemas] == documented == list(TOOL_FUNCTIONS)
    for tool in schemas:
        fn = getattr(PlanFunctions, tool["function"]["name"])
        params = [p for p in inspect.signature(fn).parameters.values() if p.name != "self"]
        schema = tool["function"]["parameters"]
        assert list(schema["properties"]) == [p.name for p in params]
        assert schema["required"] == [p.name for p in params if p.default is inspect.Parameter.empty]
        assert " ".join(tool["function"]["description"].split()) == " ".join(inspect.getdoc(fn).split())
    # the tools prompt carries no API section of its own: it names no function the tools do not offer
    text = load_prompt("tools_system.txt").template
    assert not {n for n in re.findall(r"\b([a-z_]+)\(", text)} - set(TOOL_FUNCTIONS)


def test_every_planner_api_function_has_typed_parameters_and_a_schema() -> None:
    import typing

    from capmj.agents.api.plan_functions import API_FUNCTIONS
    from capmj.agents.api.tool_schemas import function_schema

    for name in API_FUNCTIONS:
        fn = getattr(PlanFunctions, name)
        hints = typing.get_type_hints(fn)
        untyped = [p for p in inspect.signature(fn).parameters if p != "self" and p not in hints]
        assert not untyped, (name, untyped)
        assert function_schema(name)["function"]["name"] == name


def test_annotations_become_json_schema_types() -> None:
    assert json_schema(str | int) == {"anyOf": [{"type": "string"}, {"type": "integer"}]}
    assert json_schema(tuple[float, float]) == {"type": "array", "items": {"type": "number"}, "minItems": 2,
                                                "maxItems": 2}
    assert json_schema(list[str] | None) == {"anyOf": [{"type": "array", "items": {"type": "string"}},
                                                       {"type": "null"}]}
    put = next(t for t in tool_schemas() if t["function"]["name"] == "put_first_on_second")
    target = put["function"]["parameters"]["properties"]["target"]["anyOf"]
    assert {"type": "string"} in target and {"type": "array", "items": {"type": "number"}} in target
    with pytest.raises(TypeError):
        json_schema(set[int])


@pytest.mark.parametrize("example", load_prompt("tools_system.txt").examples, ids=lambda e: e.id)
def test_the_tools_prompt_example_runs_and_shows_the_real_results(example) -> None:
    """The example conversation of ``prompts/tools_system.txt``: its calls, run in order through the
    planner API on the example's scene, return the results it shows and reach the task's predicate."""
    ctx = example_context(example)
    functions = PlannerAPI(ctx).functions()
    answers = re.split(r"^Answer \d+:", example.body, flags=re.M)[1:]
    assert answers[-1].strip() == "FINISH" and len(answers) >= 3
    for n, answer in enumerate(answers[:-1], start=1):
        calls = [Call(f"ex_{n}_{i}", name, args, "tool_calls")
                 for i, (name, args) in enumerate(re.findall(r"(\w+) with (\{.*?\})(?:, then |\n)", answer))]
        assert calls, answer
        shown = answer.split("Result", 1)[1].split(":", 1)[1].strip()
        got = []
        for c in calls:
            result, error = run_call(c, functions, TOOL_FUNCTIONS)
            assert error is None, (c, error)
            got.append(result)
        assert shown == ", ".join(got)
    assert ctx.verdict().success


def test_content_calls_read_only_offered_functions_in_order() -> None:
    text = ('Sure. {"name": "get_color", "arguments": {"obj": 3}} and ```json\n{"name": "say", "parameters": '
            '{"msg": "hi"}}\n``` {"name": "rm_rf", "arguments": {}} {"not": "a call"} {broken '
            '[{"type": "function", "function": {"name": "get_obj_names", "arguments": "{}"}}]')
    calls = content_calls(text, TOOL_FUNCTIONS, 2)
    assert [(c.id, c.name, json.loads(c.arguments)) for c in calls] == [
        ("json_2_1", "get_color", {"obj": 3}), ("json_2_2", "say", {"msg": "hi"}), ("json_2_3", "get_obj_names", {})]


def example_context(example):  # noqa: ANN001, ANN201 - a prompt Example -> its EpisodeContext
    goal = example.body.split("goal: ", 1)[1].split(")", 1)[0]
    return build_context(dataclasses.replace(example, body=f"# {goal}\n"))


def test_bad_calls_are_errors_the_model_reads() -> None:
    ctx = example_context(load_prompt("tools_system.txt").examples[0])
    functions = PlannerAPI(ctx).functions()
    for call, words in ((Call("a", "exec", "{}", "tool_calls"), "there is no function 'exec'"),
                        (Call("b", "get_color", "{obj: 1", "tool_calls"), "are not JSON"),
                        (Call("c", "get_color", "[1]", "tool_calls"), "JSON object of named arguments"),
                        (Call("d", "get_color", '{"object": 1}', "tool_calls"), "unexpected keyword")):
        result, error = run_call(call, functions, TOOL_FUNCTIONS)
        assert result is None and words in str(error), (call, error)
    assert run_call(Call("e", "get_obj_positions_np", '{"names": [3]}', "tool_calls"), functions,
                    TOOL_FUNCTIONS)[0].startswith("[[")


def test_tools_take_their_own_options() -> None:
    assert LLMAgentOptions(policy="tools").max_turns == 8 and LLMAgentOptions().policy == "code"
    with pytest.raises(ConfigError, match="--policy tools takes no"):
        LLMAgentOptions(policy="tools", reporter="text")
    with pytest.raises(ConfigError, match="unknown policy"):
        LLMAgentOptions(policy="functions")
    with pytest.raises(ConfigError, match="--interaction multi"):
        LLMAgentOptions(policy="tools", feedback="image")
    with pytest.raises(ConfigError, match="--api low runs with --policy code"):
        LLMAgentOptions(policy="tools", api="low")
    bare = system_prompt(8, examples="none")
    assert "An example" not in bare and bare.startswith(system_prompt(8).split("\n\n")[0])


def test_each_turn_is_logged_with_its_calls_and_results(server: StubLLMServer) -> None:
    from test_llm_chain import MemoryRecorder

    server.respond_with(turns(lambda r: Reply.calls(("get_color", {"obj": ZONE}), ("get_color", {"obj": "nothing"})),
                              "FINISH"))
    rec = MemoryRecorder()
    result = run_episode(get_task(TASK), SEED, agent(server), recorder=rec)
    first = result.llm.attempts[0]
    assert rec.texts["llm/attempt1/planner/1/code"] == [f'get_color({{"obj": "{ZONE}"}})\nget_color({{"obj": "nothing"}})']
    assert rec.texts["llm/attempt1/planner/1/result"][0].startswith('get_color -> "orange"\nget_color -> error: ')
    assert len(rec.texts["llm/attempt1/api_calls"][0].splitlines()) == 2 == first.api_calls
    assert first.error == first.tool_calls[1].error and first.error_type == "UnknownObjectError"
    assert rec.texts["llm/attempt2/planner/1/completion"] == ["FINISH"]


@pytest.mark.parametrize("feedback", ["image", "describe"])
def test_views_or_their_description_follow_the_tool_messages(server: StubLLMServer, feedback: str) -> None:
    def respond(request: dict[str, Any]) -> Reply:
        if "The images show a robot's table" in str(request["messages"][-1]["content"]):
            return Reply.answer("Nothing moved.")
        return turns(lambda r: Reply.calls(("get_obj_names", {})), "FINISH")(request)

    server.respond_with(respond)
    result = episode(agent(server, interaction="multi", feedback=feedback))
    first = result.llm.attempts[0]
    last = [r for r in server.requests if "tools" in r][1]["messages"][-1]
    assert last["role"] == "user" and result.llm.feedback == feedback
    if feedback == "image":
        images = [p for p in last["content"] if p.get("type") == "image_url"]
        assert len(images) == first.images >= 1
    else:
        assert "What changed in the camera views: Nothing moved." in last["content"]
        assert first.described == "Nothing moved." and first.llm_calls == 2 and first.images >= 2


def test_the_offered_tools_are_part_of_the_cache_key_only_when_sent() -> None:
    from capmj.llm import cache_key

    request = {"model": "m", "api_base": None, "messages": [{"role": "user", "content": "x"}], "temperature": 0.0,
               "max_tokens": 10}
    assert cache_key(**request) == cache_key(**request, tools=None) == cache_key(**request, tools=[])
    assert cache_key(**request, tools=tool_schemas()) != cache_key(**request)
    assert cache_key(**request, tools=tool_schemas()[:1]) != cache_key(**request, tools=tool_schemas())


def test_streamed_call_pieces_are_joined_by_index() -> None:
    from types import SimpleNamespace

    from capmj.llm.stream import ToolCallParts

    def chunk(*deltas: dict[str, Any]) -> Any:
        return SimpleNamespace(choices=[SimpleNamespace(delta=SimpleNamespace(content=None, tool_calls=list(deltas)))])

    parts = ToolCallParts()
    for c in (chunk({"index": 0, "id": "a", "function": {"name": "say", "arguments": ""}}),
              chunk({"index": 1, "id": "b", "function": {"name": "get_color", "arguments": '{"ob'}}),
              chunk({"index": 0, "function": {"arguments": '{"msg": '}}),
              chunk({"index": 1, "function": {"arguments": 'j": 3}'}}),
              chunk({"index": 0, "function": {"arguments": '"hi"}'}})):
        parts.add(c)
    assert [(t.id, t.name, json.loads(t.arguments)) for t in parts.calls()] == [
        ("a", "say", {"msg": "hi"}), ("b", "get_color", {"obj": 3})]


def test_the_documented_command_runs_and_replays_exactly(server: StubLLMServer, tmp_path: Path) -> None:
    """docs/llm.md's tool-calling command, against the scripted server (one task, in this process),
    then ``replay-check`` of its folder from the cache alone."""
    from capmj.bench.cli import main
    from capmj.bench.replay_check import main as replay_check

    doc = (Path(__file__).resolve().parents[1] / "docs" / "llm.md").read_text()
    section = doc.split("## Tool calling")[1].split("\n## ")[0]
    argv = section.split("python -m capmj.bench ")[1].split("```")[0].replace("\\\n", " ").split()
    given = dict(zip(argv[::2], argv[1::2]))
    assert given["--policy"] == "tools"
    swap = {"--model": "openai/stub", "--api-base": server.base_url, "--llm-cache": str(tmp_path / "cache"),
            "--tasks": TASK, "--out": str(tmp_path / "run"), "--workers": "0"}
    argv = [x for k, v in given.items() for x in (k, swap.get(k, v))]

    def in_text(request: dict[str, Any]) -> Reply:
        return Reply.answer(json.dumps({"name": "get_obj_names", "arguments": {}}))

    server.respond_with(turns(in_text, "FINISH"))
    assert main(argv) == 0
    episodes = [json.loads(line) for line in (tmp_path / "run" / "episodes.jsonl").read_text().splitlines()]
    assert len(episodes) == 2 and all(e["llm"]["policy"] == "tools" for e in episodes)
    config = json.loads((tmp_path / "run" / "config.json").read_text())
    assert config["args"]["agent_options"]["policy"] == "tools"
    assert config["manifest"]["policy"] == {"mode": "tools", "max_turns": int(given.get("--max-turns", 8))}
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    tools = summary["overall"]["llm openai/stub"]["loop"]["tools"]
    assert tools == {"episodes": 2, "mean_turns": 2.0, "calls": 2, "content_json_calls": 2,
                     "content_json_share": 1.0, "ended_by_model": 2, "finish_agree": 0, "no_finish": 0}
    table = (tmp_path / "run" / "summary.md").read_text().split("## Tool calling (LLM agent, --policy tools)")[1]
    assert "| 2.00 | 2 | 2/2 (100 %) | 0/2 (0 %) | 0 |" in table
    server.reset()
    server.respond_with(lambda request: Reply.error(500, "must not be called"))
    assert replay_check([str(tmp_path / "run")]) == 0
    assert len(server.requests) == 0


def test_export_keeps_the_calls_and_the_tools(server: StubLLMServer, tmp_path: Path) -> None:
    from capmj.bench.cli import main
    from capmj.bench.export import chat_examples

    server.respond_with(turns(lambda r: Reply.calls(("get_color", {"obj": ZONE})), "FINISH"))
    assert main(["--agent", "llm", "--model", "openai/stub", "--api-base", server.base_url, "--policy", "tools",
                 "--tasks", TASK, "--seeds", str(SEED), "--workers", "0", "--no-probe",
                 "--out", str(tmp_path / "run")]) == 0
    first, second = chat_examples(tmp_path / "run")
    assert first["tools"] == tool_schemas() and first["messages"][-1]["tool_calls"][0]["function"] == {
        "name": "get_color", "arguments": json.dumps({"obj": ZONE})}
    assert [m["role"] for m in second["messages"]] == ["system", "user", "assistant", "tool", "assistant"]
    assert second["messages"][3] == {"role": "tool", "tool_call_id": first["messages"][-1]["tool_calls"][0]["id"],
                                     "content": '"orange"'} and second["messages"][-1]["content"] == "FINISH"
    assert all(set(e) == {"messages"} for e in chat_examples(tmp_path / "run", messages_only=True))
