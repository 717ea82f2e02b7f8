"""The LLM planner chain end to end through a real HTTP server on 127.0.0.1.

The server (tests/llm_stub_server.py) speaks the OpenAI chat API; litellm talks to it as model
"openai/stub".  Its answers are scripted test fixtures, routed by which LMP prompt a request
carries; everything else is real: prompt files, litellm HTTP, retries, cache, sandbox, planner
API, MuJoCo physics, task predicates, the episode runner.
"""

from __future__ import annotations

import base64
import io
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from capmj.agents.llm_agent.agent import LLMAgent
from capmj.agents.llm_agent.options import LLMAgentOptions
from capmj.agents.report.verdict import parse_verdict
from capmj.agents.sandbox import SandboxBudget
from capmj.llm import LLMConfig
from capmj.runner import run_episode
from capmj.tasks.registry import get_task
from llm_stub_server import Reply, StubLLMServer, prompt_text

TASK = "stack-all-blocks-on-a-zone"
SEED = 10001  # orange zone 1 (target), purple zone 2, blocks 3..7
ZONE, OTHER_ZONE = "fixed orange zone with obj_id 1", "fixed purple zone with obj_id 2"


# ------------------------------------------------------------------------------------------------
# fixtures
# ------------------------------------------------------------------------------------------------
class MemoryRecorder:
    """Keeps every text document the episode emits, by path."""

    def __init__(self) -> None:
        self.texts: dict[str, list[str]] = {}
        self.images: dict[str, np.ndarray] = {}

    def attach(self, world) -> None:  # noqa: ANN001
        pass

    def frame(self, time, poses) -> None:  # noqa: ANN001
        pass

    def primitive(self, index, time, info) -> None:  # noqa: ANN001
        pass

    def text(self, path: str, body: str, time: float | None = None) -> None:
        self.texts.setdefault(path, []).append(body)

    def image(self, path: str, rgb: np.ndarray, time: float | None = None) -> None:
        self.images[path] = rgb

    def depth(self, path: str, depth: np.ndarray, time: float | None = None) -> None:
        self.images[path] = depth

    def close(self) -> None:
        pass


def lmp_of(request: dict[str, Any]) -> str:
    """Which LMP a request comes from (by its prompt file's first instruction line)."""
    text = prompt_text(request)
    markers = {
        "You check from a list of object poses": "reporter_direct",
        "You compare measured scene facts with a goal": "reporter_checked",
        "Write the plan for the goal in the last comment": "planner",
        "Set ret_val to the object names": "parse_obj_name",
        "Set ret_val to the position": "parse_position",
        "Define the function used in the last comment": "parse_function",
        "Judge whether the goal in the last comment": "parse_completion",
        "You check whether a robot completed a tabletop task": "vlm_reporter",
    }
    for marker, name in markers.items():
        if marker in text:
            return name
    raise AssertionError(f"unrecognised request: {text[:300]!r}")


def last_user_text(request: dict[str, Any]) -> str:
    content = request["messages"][-1]["content"]
    return content if isinstance(content, str) else " ".join(p.get("text", "") for p in content)


def code(text: str) -> str:
    return f"```python\n{text.strip()}\n```"


class Router:
    """Responder: answers per LMP; each handler gets the request and returns text or a Reply."""

    def __init__(self, **handlers: str | Reply | Callable[[dict[str, Any]], str | Reply]) -> None:
        self.handlers = handlers
        self.seen: list[str] = []

    def __call__(self, request: dict[str, Any]) -> str | Reply:
        lmp = lmp_of(request)
        self.seen.append(lmp)
        handler = self.handlers.get(lmp)
        if handler is None:
            raise AssertionError(f"no scripted answer for {lmp}")
        return handler(request) if callable(handler) else handler


def agent(server: StubLLMServer, *, llm: dict[str, Any] | None = None, **options: Any) -> LLMAgent:
    """The agent against the stub server: ``llm`` sets fields of its LLMConfig, ``options`` of its LLMAgentOptions."""
    config = LLMConfig("openai/stub", api_base=server.base_url, **{"backoff_s": 0.0, "timeout_s": 10.0, **(llm or {})})
    return LLMAgent(config, LLMAgentOptions(**options))


def a_transcript(a: LLMAgent) -> list[dict[str, Any]]:
    return [c.to_dict() for c in a.transcript]


def episode(a: LLMAgent, recorder: MemoryRecorder | None = None):
    return run_episode(get_task(TASK), SEED, a, recorder=recorder)


# Scripted answers (fixtures).  The reporter's checking code is real code judging the real scene.
WRONG_PLAN = """
# stack the blocks (wrongly) in the purple zone
blocks = parse_obj_name('all the blocks', f'objects = {get_obj_names()}')
zone = pick_zone('purple')
for block in blocks:
    put_first_on_second(block, zone)
"""
RIGHT_PLAN = """
# the scene must have been reset: nothing may lie in the purple zone any more
assert [n for n in is_target_occupied('fixed purple zone with obj_id 2') if ' block ' in n] == []
blocks = parse_obj_name('all the blocks', f'objects = {get_obj_names()}')
zone = pick_zone('orange')
for block in blocks:
    put_first_on_second(block, zone)
say('stacked in the orange zone')
"""
OBJ_NAMES = "ret_val = [name for name in objects if ' block ' in name]"
PICK_ZONE = """
def pick_zone(color):
    return zones_of_color(color)[0]
"""
ZONES_OF_COLOR = """
def zones_of_color(color):
    return [name for name in get_obj_names() if ' zone ' in name and get_color(name) == color]
"""
REPORTER = """
poses = get_obj_pos_dict()
zx, zy, _ = poses['fixed orange zone with obj_id 1'][0]
blocks = sorted([n for n in poses if ' block ' in n], key=lambda n: poses[n][0][2])
inside = [n for n in blocks if abs(poses[n][0][0] - zx) < 0.06 and abs(poses[n][0][1] - zy) < 0.06]
stacked = all(abs(poses[b][0][2] - poses[a][0][2] - 0.04) < 0.015 for a, b in zip(blocks, blocks[1:]))
judge = stacked and len(inside) == len(blocks)
reason = f'{len(inside)} of {len(blocks)} blocks in the orange zone'
"""


def parse_function_answer(request: dict[str, Any]) -> str:
    q = last_user_text(request).strip().splitlines()[-1]
    if "pick_zone(" in q:
        return code(PICK_ZONE)
    if "zones_of_color(" in q:
        return code(ZONES_OF_COLOR)
    raise AssertionError(q)


def planner_answer(request: dict[str, Any]) -> str:
    replanning = len(request["messages"]) == 4
    return code(RIGHT_PLAN if replanning else WRONG_PLAN)


def full_router() -> Router:
    return Router(planner=planner_answer, parse_obj_name=code(OBJ_NAMES),
                  parse_function=parse_function_answer, parse_completion=code(REPORTER))


# ------------------------------------------------------------------------------------------------
# the closed loop
# ------------------------------------------------------------------------------------------------
def test_failed_attempt_is_judged_reset_and_replanned_to_success(server: StubLLMServer) -> None:
    router = full_router()
    server.respond_with(router)
    rec = MemoryRecorder()
    result = episode(agent(server, reporter="text", attempts=3), rec)

    assert result.success, (result.error, result.diagnostics)
    assert result.error is None
    assert result.attempts == 2 and result.primitives == 10  # 5 + 5: the old plan was not re-run
    llm = result.llm
    first, second = llm.attempts
    assert first.verdict is False and first.error is None and "0 of 5" in first.report
    assert second.verdict is True and second.reset is True and second.primitives == 5
    assert "pick_zone" in second.code and "def zones_of_color" in second.code  # synthesised
    assert second.said == ("stacked in the orange zone",)
    assert llm.stopped == "reporter: achieved"
    # planner, parse_obj_name, parse_function x2, parse_completion per attempt
    assert router.seen == ["planner", "parse_function", "parse_function", "parse_obj_name", "parse_completion"] * 2
    assert llm.calls == 10 == len(server.requests) and llm.cached_calls == 0
    assert llm.prompt_tokens > 0 and llm.completion_tokens > 0
    # the re-plan carried the old plan and the failure report, then asked for a new plan
    replan = server.requests[5]["messages"]
    assert [m["role"] for m in replan] == ["system", "user", "assistant", "user"]
    assert "purple" in replan[2]["content"] and "did not achieve the goal" in replan[3]["content"]
    assert "0 of 5 blocks in the orange zone" in replan[3]["content"]
    assert "objects = [" in replan[3]["content"] and result.goal in replan[3]["content"]
    # everything is in the log
    for k in (1, 2):
        for path in ("planner/1/prompt", "planner/1/completion", "planner/1/code",
                     "parse_obj_name/1/code", "parse_obj_name/1/result", "parse_function/1/completion",
                     "parse_function/2/code", "parse_completion/1/code", "parse_completion/1/result",
                     "api_calls", "verdict"):
            assert f"llm/attempt{k}/{path}" in rec.texts, (k, path)
    assert "put_first_on_second" in rec.texts["llm/attempt1/api_calls"][0]
    assert rec.texts["llm/attempt1/verdict"] == ["not achieved (reporter verdict from code; task predicate: False)"]
    # per attempt: where the verdict came from, the predicate on the same state, whether the plan changed
    assert (first.verdict_source, first.predicate, first.code_differs) == ("code", False, None)
    assert (second.verdict_source, second.predicate, second.code_differs) == ("code", True, True)
    assert first.temperatures == (0.0,) and second.temperatures == (0.7,)
    assert first.seeds == (None,) and isinstance(second.seeds[0], int)
    assert "seed" not in server.requests[0] and server.requests[5]["seed"] == second.seeds[0]


def test_helper_lmp_results_are_used_by_the_plan(server: StubLLMServer) -> None:
    """One attempt, no reporter: the right plan alone solves the task."""
    echo = "import numpy as np\nfrom env_utils import get_obj_names, put_first_on_second\n"
    server.respond_with(Router(planner=code(echo + RIGHT_PLAN), parse_obj_name=code(OBJ_NAMES),
                               parse_function=parse_function_answer))
    a = agent(server)
    rec = MemoryRecorder()
    result = episode(a, rec)
    assert result.success and result.error is None and result.attempts == 1
    # harmless echoes of the prompt's import header are dropped (import os would not be)
    assert rec.texts["llm/attempt1/planner/1/removed_imports"] == [echo.strip()]
    lmps = [c["lmp"] for c in a_transcript(a)]
    assert lmps == ["planner", "parse_function", "parse_function", "parse_obj_name"]
    name_call = a.transcript[3]
    assert "movable small cyan block with obj_id 3" in (name_call.result or "")
    assert [c.lmp for c in a.transcript] == lmps
    assert result.llm.stopped == "plan finished"


# ------------------------------------------------------------------------------------------------
# malformed completions
# ------------------------------------------------------------------------------------------------
MALFORMED = {
    "no_code": ("I am sorry, but I cannot help with stacking blocks today.", "no code in completion"),
    "syntax_error": (code("for block in\n    put_first_on_second(block)"), "SyntaxError"),
    "infinite_loop": (code("while True:\n    pass"), "executed-line budget of 100000 lines exceeded"),
    "import_os": (code("import os\nos.system('echo hi')"), "import statements are not allowed"),
    "dunder_escape": (code("x = ().__class__.__bases__[0].__subclasses__()"), "attribute"),
    "huge_allocation": (code("x = [0] * (10 ** 10)"), "elements"),
    "raises": (code("put_first_on_second('the green block', 'fixed orange zone with obj_id 1')"), "unknown object"),
}


@pytest.mark.parametrize("case", list(MALFORMED))
def test_malformed_completion_ends_the_attempt_with_a_recorded_error(server: StubLLMServer, case: str) -> None:
    answer, message = MALFORMED[case]
    server.respond_with(Router(planner=answer))
    rec = MemoryRecorder()
    a = agent(server, plan_budget=SandboxBudget(wall_s=30, max_api_calls=100))
    result = episode(a, rec)  # the runner returns a result, nothing escapes
    assert not result.success
    assert result.error is not None and result.error.startswith(("PlanError", "BudgetExceeded")), result.error
    assert message in result.error, result.error
    (attempt,) = result.llm.attempts
    assert attempt.error_kind == "plan" and message in attempt.error
    assert result.primitives == 0
    assert message in rec.texts["llm/attempt1/error"][0]
    assert len(server.requests) == 1


def test_code_error_is_followed_by_a_replan_with_the_error(server: StubLLMServer) -> None:
    def planner(request: dict[str, Any]) -> str:
        if len(request["messages"]) == 2:
            return code("for block in\n    oops")
        assert "SyntaxError" in request["messages"][3]["content"]
        return code(RIGHT_PLAN)

    server.respond_with(Router(planner=planner, parse_obj_name=code(OBJ_NAMES),
                               parse_function=parse_function_answer))
    result = episode(agent(server, attempts=2))
    assert result.success and result.error is None and result.attempts == 2
    first, second = result.llm.attempts
    assert "SyntaxError" in first.error and second.error is None


def test_function_synthesis_depth_is_bounded(server: StubLLMServer) -> None:
    def endless(request: dict[str, Any]) -> str:
        q = last_user_text(request).strip().splitlines()[-1]
        n = int(q.split("helper_")[1].split("(")[0])
        return code(f"def helper_{n}(x):\n    return helper_{n + 1}(x)")

    server.respond_with(Router(planner=code("y = helper_0(1)"), parse_function=endless))
    a = agent(server, max_fn_depth=3)
    result = episode(a)
    assert result.error is not None and "synthesis depth 3" in result.error
    assert [c.lmp for c in a.transcript] == ["planner"] + ["parse_function"] * 3


# ------------------------------------------------------------------------------------------------
# provider failures
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("failure", ["timeout", "http500"])
def test_provider_failure_is_retried_then_recorded(server: StubLLMServer, failure: str) -> None:
    bad = Reply.delayed(3.0, code(RIGHT_PLAN)) if failure == "timeout" else Reply.error(500, "boom")
    server.script(bad, bad, bad)
    a = agent(server, attempts=3, llm={"max_retries": 2, "timeout_s": 0.5 if failure == "timeout" else 10.0})
    result = episode(a)
    assert not result.success
    assert result.error is not None and result.error.startswith("LLMError"), result.error
    assert len(server.requests) == 3  # 1 call + 2 retries, then no further attempt
    (attempt,) = result.llm.attempts
    assert attempt.error_kind == "llm" and result.llm.stopped == "llm error"
    assert result.llm.failed_calls == 1 and result.primitives == 0


def test_provider_failure_inside_a_helper_lmp_ends_the_attempts(server: StubLLMServer) -> None:
    server.respond_with(Router(planner=code(RIGHT_PLAN), parse_function=parse_function_answer,
                               parse_obj_name=Reply.error(500, "down")))
    result = episode(agent(server, attempts=3, llm={"max_retries": 1}))
    assert result.error is not None and result.error.startswith("LLMError")
    assert len(result.llm.attempts) == 1 and result.llm.attempts[0].error_kind == "llm"


# ------------------------------------------------------------------------------------------------
# cache
# ------------------------------------------------------------------------------------------------
def test_rerun_from_the_disk_cache_makes_no_http_calls(server: StubLLMServer, tmp_path: Path) -> None:
    server.respond_with(full_router())
    first = episode(agent(server, reporter="text", attempts=2, llm={"cache_dir": tmp_path}))
    # identical helper questions of attempt 2 are already answered from the cache
    assert first.success and first.llm.calls == 10 and first.llm.cached_calls == 3
    assert len(server.requests) == 7
    server.reset()
    server.respond_with(lambda request: Reply.error(500, "must not be called"))
    again = episode(agent(server, reporter="text", attempts=2, llm={"cache_dir": tmp_path}))
    assert len(server.requests) == 0
    assert again.llm.cached_calls == again.llm.calls == 10 and again.llm.cost_usd == 0
    same = ("success", "progress", "reward", "primitives", "attempts", "error", "sim_s", "diagnostics")
    assert {k: getattr(again, k) for k in same} == {k: getattr(first, k) for k in same}
    strip = lambda r: [a.to_dict() for a in r.llm.attempts]  # noqa: E731
    assert strip(again) == strip(first)


# ------------------------------------------------------------------------------------------------
# VLM reporter
# ------------------------------------------------------------------------------------------------
def _png(part: dict[str, Any]) -> np.ndarray:
    from PIL import Image

    url = part["image_url"]["url"]
    assert url.startswith("data:image/png;base64,")
    return np.asarray(Image.open(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))).convert("RGB"))


def test_vlm_reporter_sends_images_and_parses_the_verdict_from_code(server: StubLLMServer) -> None:
    pytest.importorskip("PIL")
    server.respond_with(Router(planner=code(RIGHT_PLAN), parse_obj_name=code(OBJ_NAMES),
                               parse_function=parse_function_answer,
                               vlm_reporter="The tower looks wrong.\n" + code(
                                   "judge = False\nreason = 'the blocks are not stacked'")))
    rec = MemoryRecorder()
    result = episode(agent(server, reporter="vlm"), rec)
    (attempt,) = result.llm.attempts
    if any("no images" in e for e in attempt.reporter_errors):
        pytest.skip(f"no OpenGL renderer: {attempt.reporter_errors}")
    assert attempt.verdict is False and "not stacked" in attempt.report
    assert attempt.verdict_source == "code" and attempt.predicate is True  # a false negative
    assert result.success  # the predicate judges the scene, the reporter only drives re-planning
    vlm = [r for r in server.requests if lmp_of(r) == "vlm_reporter"]
    assert len(vlm) == 1
    parts = vlm[0]["messages"][-1]["content"]
    images = [_png(p) for p in parts if p.get("type") == "image_url"]
    assert len(images) == 3
    before, after, depth = images
    assert before.shape == after.shape == depth.shape == (480, 640, 3)
    assert np.abs(before.astype(int) - after.astype(int)).mean() > 0.5  # blocks moved
    # the depth image is visible: bright on average, many distinct colours, not the original's black
    assert depth.mean() > 40 and len(np.unique(depth.reshape(-1, 3), axis=0)) > 50
    text = " ".join(p.get("text", "") for p in parts if p.get("type") == "text")
    assert result.goal in text and "movable small cyan block with obj_id 3" in text
    assert "llm/vlm/initial_rgb" in rec.images and "llm/attempt1/vlm_reporter/1/final_rgb" in rec.images


@pytest.mark.parametrize(("answer", "verdict"), [
    (code("judge = False"), False),
    (code("judge = True\nreason = 'done'"), True),
    ("judge = True", True),
    ("The goal is not True yet.", None),           # substring search would have said True
    (code("judge = 'True'"), None),                 # a string is not a verdict
    (code("judge = True\njudge = False"), None),    # contradictory
    (code("reason = 'looks fine'"), None),
    (code("judge = (\nreason = 'x'\njudge = False"), False),  # broken block: line-wise parse
    (code("judge = not False"), None),              # not a literal: nothing is evaluated
])
def test_parse_verdict(answer: str, verdict: bool | None) -> None:
    judge, _reason, problem = parse_verdict(answer)
    assert judge is verdict
    assert (problem is None) == (verdict is not None)


def test_agent_options_match_the_bench_factory() -> None:
    from capmj.agents.factory import make_agent
    from capmj.errors import ConfigError

    a = make_agent("llm", model="gpt-4o-mini", api_base=None, reporter="vlm", attempts=2, temperature=0)
    assert a.name == "llm" and a.model == "gpt-4o-mini" and a.options.attempts == 2 and a.options.reporter == "vlm"
    assert a.config == LLMConfig("gpt-4o-mini", temperature=0.0) and isinstance(a.config.temperature, float)
    assert make_agent("llm").model == "gpt-4o-mini"  # the default model
    with pytest.raises(ConfigError, match="unknown reporter 'audio'"):
        make_agent("llm", model="gpt-4o-mini", reporter="audio")
    with pytest.raises(ConfigError, match="attempts must be >= 1"):
        LLMAgentOptions(attempts=0)
    with pytest.raises(ConfigError, match="does not take option.*bogus"):
        make_agent("llm", bogus=1)
    with pytest.raises(ConfigError, match="max_tokens must be int"):
        make_agent("llm", max_tokens="many")
    with pytest.raises(ConfigError, match="LLMAgent takes an LLMConfig"):
        LLMAgent("gpt-4o-mini")  # type: ignore[arg-type]  # the keyword form of before is refused clearly
    with pytest.raises(ConfigError, match="episode_max_cost_usd needs a price"):
        LLMAgent(LLMConfig("openai/no-such-model"), LLMAgentOptions(episode_max_cost_usd=1.0))
    assert LLMAgentOptions(price="1,2").price is not None and LLMAgentOptions(attempts="2").attempts == 2


# ------------------------------------------------------------------------------------------------
# code preparation (pure functions)
# ------------------------------------------------------------------------------------------------
def test_undefined_calls_finds_only_missing_bare_calls() -> None:
    from capmj.agents.lmp.codeprep import undefined_calls

    src = ("def helper(x):\n    return x\n"
           "a = helper(get_obj_pos('b'))\n"
           "for n in sorted(objects):\n    b = missing_one(n, len(objects))\n"
           "c = np.mean(other_missing([1]))\n"
           "d = eval('1')\n"            # forbidden names are left to the sandbox
           "e = [z for z in range(3)]\n")
    found = undefined_calls(src, {"get_obj_pos", "objects"})
    assert [(name, line) for name, line, _ in found] == [("missing_one", 5), ("other_missing", 6)]
    assert found[0][2] == "b = missing_one(n, len(objects))"
    assert undefined_calls("def broken(:\n", set()) == []


def test_strip_benign_imports_keeps_dangerous_ones() -> None:
    from capmj.agents.lmp.codeprep import strip_benign_imports

    src = ("import numpy as np\nfrom env_utils import get_obj_pos\nimport os\n"
           "from plan_utils import secret_tool\nx = 1\n")
    out, removed = strip_benign_imports(src, {"get_obj_pos", "np"})
    assert removed == ["import numpy as np", "from env_utils import get_obj_pos"]
    assert "import os" in out and "from plan_utils import secret_tool" in out
    assert len(out.splitlines()) == len(src.splitlines())  # line numbers of errors stay right


# ------------------------------------------------------------------------------------------------
# the way users run it: the bench CLI, a worker process, an .rrd read back
# ------------------------------------------------------------------------------------------------
def test_bench_cli_runs_the_llm_agent_in_a_worker_and_logs_every_prompt(server: StubLLMServer, tmp_path: Path) -> None:
    import json

    from capmj.bench.cli import main
    from capmj.replay import read_episode

    server.respond_with(full_router())
    out = tmp_path / "run"
    # the thesis's chain, which the router answers: since #49 item 7 --reporter text alone runs careful + relations
    rc = main(["--agent", "llm", "--model", "openai/stub", "--api-base", server.base_url, "--reporter", "text",
               "--loop-policy", "thesis", "--reporter-prompt", "thesis",
               "--attempts", "3", "--tasks", TASK, "--seeds", str(SEED), "--workers", "1", "--out", str(out),
               "--no-progress"])
    assert rc == 0
    (line,) = (out / "episodes.jsonl").read_text().splitlines()
    rec = json.loads(line)
    assert rec["success"] is True and rec["error"] is None, rec
    assert rec["agent"] == "llm" and rec["model"] == "openai/stub" and rec["attempts"] == 2
    assert rec["llm"]["calls"] == 10 == len(server.requests)  # the worker really talked HTTP
    log = read_episode(out / rec["rrd"])
    assert log.summary["success"] is True and log.summary["model"] == "openai/stub"
    for k in (1, 2):
        assert f"llm/attempt{k}/planner/1/prompt" in log.texts
        assert f"llm/attempt{k}/planner/1/code" in log.texts
    assert "put_first_on_second" in log.texts["llm/attempt2/planner/1/code"][0]
    # the closed-loop figures are in summary.json and summary.md
    loop = json.loads((out / "summary.json").read_text())["overall"]["llm openai/stub"]["loop"]
    assert (loop["reporter_runs"], loop["verdicts"], loop["agree"], loop["compared"]) == (2, 2, 2, 2)
    assert (loop["replans"], loop["identical_replans"]) == (1, 0)
    assert loop["mean_tokens"] == rec["llm"]["prompt_tokens"] + rec["llm"]["completion_tokens"] > 0
    assert "| **Overall** | llm openai/stub | 1/1 (100 %) | 2.00 | 2/2 (100 %) |" in (out / "summary.md").read_text()


def test_a_plan_running_on_into_the_next_example_is_cut_at_the_stop_sequence(server: StubLLMServer) -> None:
    """A small model writes its plan, then the prompt's next few-shot example (issue #27): only the
    plan runs; the copied example (another scene's names, an undefined call) never does."""
    plan = RIGHT_PLAN.replace("assert [n for n in is_target_occupied('fixed purple zone with obj_id 2') "
                              "if ' block ' in n] == []\n", "")
    run_on = (plan.strip() + "\n\nobjects = ['movable small cyan block with obj_id 7']\n"
              "# Put the cyan block in the bowl.\nput_first_on_second('movable small cyan block with obj_id 7', "
              "'fixed blue bowl with obj_id 9')\nnot_a_function()\n")
    router = full_router()
    router.handlers["planner"] = run_on
    server.respond_with(router)
    result = episode(agent(server, attempts=1))
    assert result.success and result.error is None, result.error
    planner_requests = [r for r in server.requests if lmp_of(r) == "planner"]
    assert planner_requests[0]["stop"] == ["\n\nobjects = ["]
    assert all(r["stop"] == ["\n\n# define function:"] for r in server.requests if lmp_of(r) == "parse_function")
    (first,) = result.llm.attempts
    assert "obj_id 7" not in (first.code or "") and "not_a_function" not in (first.code or "")
