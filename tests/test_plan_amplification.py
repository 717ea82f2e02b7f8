"""Plans that amplify a small object into a huge text, array or number of LLM calls, and plans that
read a key: each refused before the harm, as a recorded failure of its episode (issue #45).

Peak memory is measured with ``tracemalloc`` (it sees Python objects and numpy's buffers): every
hostile plan here, unguarded, allocates hundreds of megabytes, so a peak of a few megabytes shows
the refusal came before the allocation.  The LLM paths run against the scripted local server of
``tests/llm_stub_server.py``; no real LLM is asked.
"""

from __future__ import annotations

import os
import pickle
import time
import tracemalloc
from collections.abc import Callable, Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
from hostile_plans import ALIASED, HOSTILE_PLANS, PLANTED_KEY, layer_of
from llm_stub_server import StubLLMServer, prompt_text

from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.llm_agent.agent import LLMAgent
from capmj.agents.llm_agent.options import LLMAgentOptions
from capmj.agents.lmp.session import DEFAULT_EPISODE_MAX_HELPER_CALLS, LMPSession
from capmj.agents.sandbox import SandboxBudget, check_code, run_code
from capmj.agents.sandbox.sizes import array_elements, broadcast_elements, capped_text, preview, text_length
from capmj.bench.failures import classify
from capmj.bench.migrate import as_record
from capmj.bench.pool import spawn_pool
from capmj.bench.ray_executor import FORWARDED_ENV
from capmj.bench.results import sanitize
from capmj.bench.worker import AgentSpec, Worker
from capmj.errors import (BudgetExceeded, HelperCallsExceeded, PlanError, SandboxViolation, TextBudgetExceeded,
                          error_facts)
from capmj.llm import LLMConfig, keys
from capmj.records import EpisodeResult
from capmj.runner import run_episode
from capmj.sim.objects import ObjectSpec
from capmj.tasks.registry import get_task
from test_api import make_ctx

MB = 1 << 20
BOUND = 20 * MB
"""Peak allocation a refused plan may reach (unguarded, each of them reaches hundreds of MB)."""


def peak_of(fn: Callable[[], Any]) -> tuple[BaseException | None, int]:
    """``fn()``'s exception (None) and the peak bytes it allocated."""
    tracemalloc.start()
    try:
        fn()
        error = None
    except BaseException as exc:  # noqa: BLE001 - the caller asserts on it
        error = exc
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return error, peak


def refused(code: str, kind: type[BaseException], env: dict[str, Any] | None = None, **kw: Any) -> PlanError:
    """Run ``code``: it must fail with a PlanError whose root class is ``kind``, within :data:`BOUND`."""
    t0 = time.perf_counter()
    error, peak = peak_of(lambda: run_code(code, env or {}, program="the plan", **kw))
    assert isinstance(error, PlanError), error
    assert error_facts(error)[0] == kind.__name__, (error_facts(error), error)
    assert peak < BOUND, f"{peak / MB:.0f} MB allocated before the refusal"
    assert time.perf_counter() - t0 < 3
    return error


@pytest.fixture()
def api():
    ctx = make_ctx([ObjectSpec(1, "block", "red", (0.4, -0.1, 0.02), size="small"),
                    ObjectSpec(2, "block", "blue", (0.6, 0.1, 0.02), size="small")])
    return PlannerAPI(ctx)


# ------------------------------------------------------------------------------------------------
# text: say, print, str/repr/f-strings/format/%, error messages, the call log
# ------------------------------------------------------------------------------------------------
def test_say_of_a_reused_inner_list_is_refused_before_its_text_is_made(api: PlannerAPI) -> None:
    error = refused(ALIASED + "say(c)\n", TextBudgetExceeded, api.functions())
    assert "max_said_chars" in str(error) and "line 4 of the plan" in str(error)
    assert api.messages == [] and api.said_chars == 0
    log = api.call_log[-1]  # the call log's summary of the argument is cut, never made whole
    assert log["fn"] == "say" and len(log["args"][0]) <= 120 and "TextBudgetExceeded" in log["error"]


def test_say_budget_cannot_be_caught_by_the_plan(api: PlannerAPI) -> None:
    code = ALIASED + "try:\n    say(c)\nexcept Exception:\n    pass\nsay('carried on')\n"
    refused(code, TextBudgetExceeded, api.functions())
    assert api.messages == []


def test_say_keeps_its_messages_and_counts_them(api: PlannerAPI) -> None:
    run_code("say('hello')\nsay([1, 2.5, 'x'])\n", api.functions())
    assert api.messages == ["hello", "[1, 2.5, 'x']"] and api.said_chars == 18
    code = "for i in range(300):\n    say('x' * 400)\n"  # 120 000 characters in small messages
    refused(code, TextBudgetExceeded, PlannerAPI(api._ctx).functions())


def test_print_of_a_reused_inner_list_is_refused(api: PlannerAPI) -> None:
    out: list[str] = []
    error = refused(ALIASED + "print('lists:', c)\n", TextBudgetExceeded, output=out)
    assert out == [] and "print()" in str(error) and "max_text_chars" in str(error)
    # many small prints count together; a long separator counts once per gap
    refused("for i in range(2000):\n    print('y' * 600)\n", TextBudgetExceeded, output=[])
    refused("print(*range(100), sep='-' * 20000)\n", TextBudgetExceeded, output=[])


def test_print_output_is_unchanged() -> None:
    out: list[str] = []
    run_code("print('a', 1, sep='-')\nprint(np.array([1, 2]))\nprint('x', end='!')\nprint(None, [1, (2,)], sep=None)",
             {}, output=out)
    assert out == ["a-1", "[1 2]", "x!", "None [1, (2,)]"]


@pytest.mark.parametrize("line", ["s = str(c)", "s = repr(c)", "s = f'{c}'", "s = f'{c!r:>5}'", "s = '{}'.format(c)",
                                  "s = '{x}'.format_map({'x': c})", "s = str.format('{}', c)", "s = '%s' % (c,)",
                                  "s = '%r' % [c]", "s = str(object=c)", "s = list(map(repr, [c]))",
                                  "s = ', '.join(str(b) for b in c)"])
def test_text_of_a_reused_inner_list_is_refused(line: str) -> None:
    error = refused(ALIASED + line + "\n", TextBudgetExceeded)
    assert "max_text_chars" in str(error)


def test_joining_texts_made_through_an_alias_stops_early() -> None:
    error = refused(ALIASED + "s = ''.join(map(str, c))\n", BudgetExceeded,  # str(b): 3 MB each, 100 of them
                    budget=SandboxBudget(max_elements=10**6))
    assert ".join()" in str(error)


def test_small_texts_are_made_as_before() -> None:
    ns = run_code("x = [1, 2.5, None]\na = str(x)\nb = repr('q')\nc = f'{x!r:>20}|{3:03d}'\nd = '{} {k}'.format(1, k=2)\n"
                  "e = '%s-%d' % ('a', 3)\nf = '{x}'.format_map({'x': 7})\n", {})
    assert (ns["a"], ns["b"], ns["c"], ns["d"], ns["e"], ns["f"]) == (
        "[1, 2.5, None]", "'q'", "      [1, 2.5, None]|003", "1 2", "a-3", "7")


def test_an_error_raised_with_a_huge_value_is_shown_cut() -> None:
    error = refused(ALIASED + "raise ValueError(c)\n", ValueError)
    assert "ValueError: [[[0, 0" in str(error) and len(str(error)) < 10_500


def test_sizes_walk_shared_lists_once_and_stop_at_the_cap() -> None:
    a = [0] * 1000
    b = [a] * 1000
    c = [b] * 100
    t0 = time.perf_counter()
    assert text_length(c, 10**6) is None and capped_text(c, 10**6) is None
    assert array_elements(c, 10**7) > 10**7 and array_elements(b, 10**7) == 10**6
    assert len(preview(c, 50)) == 50 and preview(c, 50).startswith("[[[0, 0")
    assert time.perf_counter() - t0 < 1
    d: dict[str, Any] = {"k": [1]}
    d["self"] = d
    for value in ([1, (2,), {"a": [3.5, None]}], (1,), d, {1: 2}.items(), slice(1, [2], None), ValueError("m", [1]),
                  KeyError("k"), frozenset(), "é'\n", b"\x00"):
        assert text_length(value, 1000, as_repr=True) == len(repr(value))
        assert text_length(value, 1000) == len(str(value))
    assert broadcast_elements([[1], [2]], [[1, 2, 3]]) == 6


# ------------------------------------------------------------------------------------------------
# arrays: broadcasting, nested lists, every numpy constructor
# ------------------------------------------------------------------------------------------------
BIG_COLUMN, BIG_ROW = "np.ones((12000, 1))", "np.ones((1, 12000))"


@pytest.mark.parametrize("line", [
    f"x = {BIG_COLUMN} + {BIG_ROW}", f"x = {BIG_COLUMN} - {BIG_ROW}", f"x = {BIG_COLUMN} * {BIG_ROW}",
    f"x = {BIG_COLUMN} / {BIG_ROW}", f"x = {BIG_COLUMN} ** {BIG_ROW}", f"x = {BIG_COLUMN} % {BIG_ROW}",
    f"x = {BIG_COLUMN} @ {BIG_ROW}", f"x = {BIG_COLUMN} < {BIG_ROW}", f"x = {BIG_COLUMN} == {BIG_ROW}",
    f"x = {BIG_ROW} in {BIG_COLUMN}", f"x = {BIG_COLUMN} < {BIG_ROW} < 2",
    f"x = {BIG_COLUMN}\nx -= {BIG_ROW}", f"x = 1\nx += {BIG_COLUMN} + {BIG_ROW}",
    f"x = np.maximum({BIG_COLUMN}, {BIG_ROW})", f"x = np.hypot({BIG_COLUMN}, {BIG_ROW})",
    f"x = np.where({BIG_COLUMN} > 0, {BIG_COLUMN}, {BIG_ROW})", f"x = np.dot({BIG_COLUMN}, {BIG_ROW})",
    f"x = {BIG_COLUMN}.dot({BIG_ROW})", f"x = {BIG_COLUMN}.clip(0, {BIG_ROW})",
    f"x = np.clip({BIG_COLUMN}, 0, {BIG_ROW})", f"x = np.isclose({BIG_COLUMN}, {BIG_ROW})",
    f"x = np.allclose({BIG_COLUMN}, {BIG_ROW})",
])
def test_broadcast_results_are_refused_before_they_are_computed(line: str) -> None:
    error = refused(line + "\n", BudgetExceeded)
    assert "144000000 elements" in str(error) and "max_elements" in str(error)


@pytest.mark.parametrize("line", [
    "x = np.array(c)", "x = np.asarray(c, dtype=np.float32)", "x = np.float64(c)", "x = np.sqrt(c)",
    "x = np.mean(c)", "x = np.zeros(1) + c", "x = np.float64(1.0) * c", "x = np.tile(c, 1)",
    "x = np.zeros_like(c)", "x = np.concatenate([np.zeros(10**6)] * 100)", "x = np.stack([np.zeros(10**6)] * 100)",
    "x = np.linalg.norm(c)", "x = np.random.permutation(c)", "x = np.array(['x' * 10**6] * 100)",
    "x = np.unique(c)",
])
def test_arrays_of_reused_nested_lists_are_refused_before_numpy_makes_them(line: str) -> None:
    refused(ALIASED + line + "\n", BudgetExceeded)


def test_small_numpy_work_is_unchanged() -> None:
    ns = run_code("a = np.ones((3, 1)) + np.arange(3)\nb = np.array([[1, 2], [3, 4]], dtype=np.float32)\n"
                  "c = isinstance(np.float64(2.0), np.float64) and type(np.float64(1)) == np.float64\n"
                  "d = 0 < 1 <= 1 < 2\ne = [1] in [[1]] and 3 not in [1, 2] and None is None\n"
                  "f = np.sum(np.float64([1.5, 2.5]))\ng = np.maximum([1, 5], np.array([3, 2])).tolist()\n"
                  "h = np.concatenate([np.zeros(2), [1.0]]).tolist()\ni = (a @ np.ones((3, 2))).shape\n", {})
    assert ns["a"].shape == (3, 3) and str(ns["b"].dtype) == "float32" and ns["c"] is True
    assert ns["d"] is True and ns["e"] is True and ns["f"] == 4.0 and ns["g"] == [3, 5]
    assert ns["h"] == [0.0, 0.0, 1.0] and ns["i"] == (3, 2)


def test_a_chained_comparison_evaluates_each_operand_once_in_order() -> None:
    ns = run_code("seen = []\ndef v(x):\n    seen.append(x)\n    return x\nr1 = v(1) < v(0) < v(5)\n"
                  "r2 = v(1) < v(2) < v(3)\nr3 = [y for y in range(5) if 1 <= y < 3]\n", {})
    assert ns["seen"] == [1, 0, 1, 2, 3] and ns["r1"] is False and ns["r2"] is True and ns["r3"] == [1, 2]


def test_wrapped_operands_do_not_count_as_lines() -> None:
    budget = SandboxBudget(max_lines=40)  # 32 lines; each chained comparison wraps 3 operands
    run_code("n = 0\nfor i in range(10):\n    if 0 <= i < 100 and -1 < i <= 100:\n        n += 1\n", {}, budget=budget)


# ------------------------------------------------------------------------------------------------
# helper LMPs: return values, calls per episode
# ------------------------------------------------------------------------------------------------
def scripted(answers: dict[str, str], calls: list[str]) -> Callable[..., Any]:
    def complete(messages: Any, purpose: str = "", **kwargs: Any) -> Any:
        lmp = purpose.split("#")[0]
        calls.append(lmp)
        return SimpleNamespace(text=f"```python\n{answers[lmp]}```", cached=False)

    return complete


def test_a_helper_returning_a_reused_inner_list_is_refused(api: PlannerAPI) -> None:
    calls: list[str] = []
    session = LMPSession(complete=scripted({"parse_obj_name": ALIASED + "ret_val = c\n"}, calls),
                         api=api.functions(), objects_text=api.objects_text)
    code = "try:\n    names = parse_obj_name('every block')\nexcept Exception:\n    names = []\nsay(names)\n"
    error = refused(code, TextBudgetExceeded, session.plan_env())
    assert "parse_obj_name returned" in str(error) and "max_text_chars" in str(error)
    (call,) = session.transcript
    assert call.result is not None and call.result.startswith("refused: [[[0, 0") and len(call.result) < 300
    assert call.error is None and api.messages == []  # the helper's code ran; the plan asked for too much


def test_helper_calls_are_capped_per_session_by_default(api: PlannerAPI) -> None:
    calls: list[str] = []
    answers = {"parse_obj_name": "for j in range(500):\n    parse_position('a point')\nret_val = []\n",
               "parse_position": "ret_val = [0.5, 0.0]\n"}
    session = LMPSession(complete=scripted(answers, calls), api=api.functions(), objects_text=api.objects_text)
    code = "for i in range(500):\n    try:\n        parse_obj_name('the blocks')\n    except Exception:\n        pass\n"
    error = refused(code, HelperCallsExceeded, session.plan_env(), budget=SandboxBudget(max_api_calls=10**6))
    assert len(calls) == DEFAULT_EPISODE_MAX_HELPER_CALLS == 200 and session.helper_cap.used == 201
    assert "helper LMP call budget of 200 calls per episode" in str(error)
    with pytest.raises(HelperCallsExceeded):  # every later call is refused too, before the LLM
        session.parse_obj_name("again")
    assert len(calls) == 200


def code_of(text: str) -> str:
    return f"```python\n{text}\n```"


def lmp_of(request: dict[str, Any]) -> str:
    text = prompt_text(request)
    for marker, name in (("Write the plan for the goal", "planner"), ("Set ret_val to the object names", "parse_obj_name"),
                         ("Set ret_val to the position", "parse_position")):
        if marker in text:
            return name
    raise AssertionError(text[:200])


def episode_with(server: StubLLMServer, answers: dict[str, str], config: LLMConfig | None = None,
                 **options: Any) -> Any:
    server.respond_with(lambda request: code_of(answers[lmp_of(request)]))
    config = config or LLMConfig("openai/stub", api_base=server.base_url, backoff_s=0.0, timeout_s=10.0)
    result = run_episode(get_task("stack-all-blocks-on-a-zone"), 10001, LLMAgent(config, LLMAgentOptions(**options)))
    return result, as_record(EpisodeResult.from_dict(sanitize(result.to_dict())))


def test_nested_helper_calls_end_the_episode_as_a_budget_failure(server: StubLLMServer) -> None:
    plan = next(p for p in HOSTILE_PLANS if p.name == "nested_helper_calls")
    result, record = episode_with(server, {"planner": plan.code, **plan.helpers}, episode_max_helper_calls=20,
                                  attempts=3)
    assert result.error_type == "HelperCallsExceeded" and "episode_max_helper_calls" in result.error
    assert len(server.requests) == 1 + 20  # the planner, then the 20 helper calls the cap allows
    assert result.llm.stopped == "llm budget" and result.attempts == 1  # no re-plan after it
    assert classify(record) == "budget"
    assert LLMAgentOptions().episode_max_helper_calls == DEFAULT_EPISODE_MAX_HELPER_CALLS


# ------------------------------------------------------------------------------------------------
# format strings
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("template", ["{0.__globals__}", "{0[OPENAI_API_KEY]}", "{f.x}", "{:{0.real}}", "{[0]}"])
def test_format_fields_reaching_into_arguments_are_refused_statically(template: str) -> None:
    with pytest.raises(SandboxViolation, match="format field"):
        check_code(f"s = {template!r}.format(say)\n")
    with pytest.raises(SandboxViolation, match="format field"):
        check_code(f"fmt = {template!r}.format_map\n")


@pytest.mark.parametrize(("template", "line"), [
    ("'{0.__glo' + 'bals__}'", "s = t.format(abs)"),
    ("'{f.__glo' + 'bals__}'", "s = t.format_map({'f': abs})"),
    ("'{0.__glo' + 'bals__}'", "s = str.format(t, abs)"),
    ("'{0.__glo' + 'bals__}'", "g = t.format\ns = g(abs)"),
    ("'{0.__glo' + 'bals__}'", "s = list(map(t.format, [abs]))"),
    ("'{0[' + 'k]}'", "try:\n    s = t.format({'k': 1})\nexcept Exception:\n    s = 'caught'"),
    ("'{:{0.re' + 'al}}'", "s = t.format(1)"),
])
def test_format_fields_reaching_into_arguments_are_refused_at_run_time(template: str, line: str) -> None:
    error = refused(f"t = {template}\n{line}\n", SandboxViolation)
    assert "format field" in str(error) and "name arguments only" in str(error)


# ------------------------------------------------------------------------------------------------
# secrets
# ------------------------------------------------------------------------------------------------
@pytest.fixture()
def planted(monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
    """OPENAI_API_KEY planted in this process's environment; this module's store of taken keys fresh."""
    monkeypatch.setattr(keys, "_taken", {})
    monkeypatch.setenv("OPENAI_API_KEY", PLANTED_KEY)
    monkeypatch.setenv("HF_TOKEN", "hf-planted")
    yield PLANTED_KEY


def test_the_secret_rule() -> None:
    for name in ("OPENAI_API_KEY", "ANTHROPIC_AUTH_TOKEN", "HF_TOKEN", "AWS_ACCESS_KEY_ID", "AWS_SECRET_ACCESS_KEY",
                 "GOOGLE_APPLICATION_CREDENTIALS", "SSH_AUTH_SOCK", "PGPASSWORD", "gemini_api_key", "MY_APIKEY"):
        assert keys.is_secret_name(name), name
    for name in ("PATH", "HOME", "MUJOCO_GL", "CAPMJ_LLM_CACHE", "OPENAI_BASE_URL", "TOKENIZERS_PARALLELISM",
                 "KEYBOARD_LAYOUT", "LITELLM_LOCAL_MODEL_COST_MAP", "PYTHONHASHSEED"):
        assert not keys.is_secret_name(name), name
    assert not [n for n in FORWARDED_ENV if keys.is_secret_name(n)]  # Ray actors get no key either


def test_secrets_leave_the_environment_and_reach_the_client_explicitly(planted: str) -> None:
    taken = keys.take_secrets()
    assert taken["OPENAI_API_KEY"] == planted and "OPENAI_API_KEY" not in os.environ and "HF_TOKEN" not in os.environ
    assert keys.take_secrets() == taken  # idempotent
    config = LLMConfig("gpt-4o-mini")
    assert config.resolved_api_key == planted and planted not in repr(config)
    assert LLMConfig("openai/local", api_base="http://127.0.0.1:1/v1").resolved_api_key == "sk-local"
    spec = AgentSpec("llm", {"model": "gpt-4o-mini", "price": "0,0"}, api_key=planted)
    assert planted not in repr(spec) and "api_key" not in spec.options
    assert Worker(spec)._build_agent().config.api_key == planted  # workers get it in their configuration


def _environment_of_this_process() -> tuple[str, bytes]:
    return os.environ.get("OPENAI_API_KEY", ""), Path("/proc/self/environ").read_bytes()


def test_worker_processes_start_without_the_key(planted: str) -> None:
    keys.take_secrets()
    with spawn_pool(1) as pool:
        env_value, proc_environ = pool.submit(_environment_of_this_process).result(timeout=30)
    assert env_value == "" and planted.encode() not in proc_environ and b"hf-planted" not in proc_environ
    assert pickle.loads(pickle.dumps(AgentSpec("llm", api_key=planted))).api_key == planted


def test_bench_commands_take_the_secrets_first(planted: str, tmp_path: Path) -> None:
    from capmj.bench.cli import main

    assert main(["report", str(tmp_path / "none")]) == 2
    assert "OPENAI_API_KEY" not in os.environ and keys.taken_secrets()["OPENAI_API_KEY"] == planted


def test_plan_code_cannot_read_a_planted_key_while_the_request_carries_it(planted: str, server: StubLLMServer,
                                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OPENAI_BASE_URL", server.base_url)  # the provider's default server is the stub
    keys.take_secrets()  # as the bench does when it starts
    plan = next(p for p in HOSTILE_PLANS if p.name == "env_key_into_helper_question")
    secrets_seen: list[bool] = []

    def answer(request: dict[str, Any]) -> str:  # runs while the episode's code runs
        secrets_seen.append(any(keys.is_secret_name(k) for k in os.environ))
        return code_of({"planner": "names = parse_obj_name('the blocks')\n" + plan.code,
                        "parse_obj_name": "ret_val = objects"}[lmp_of(request)])

    server.respond_with(answer)
    config = LLMConfig("gpt-4o-mini", backoff_s=0.0, timeout_s=10.0, max_retries=0)
    result = run_episode(get_task("stack-all-blocks-on-a-zone"), 10001, LLMAgent(config, LLMAgentOptions(price="0,0")))
    assert result.error_type == "SandboxViolation" and "format field" in result.error
    assert len(server.request_log) == 2 and secrets_seen == [False, False]
    assert all(r.headers["Authorization"] == f"Bearer {planted}" for r in server.request_log)
    assert planted not in repr(server.requests) and planted not in repr(result.to_dict())
    assert layer_of(result.error_type, result.error, static=False) == "format guard"
