"""The closed loop closes: the reporter reaches a verdict, unknown verdicts follow the policy,
re-plans differ, and the reporter's accuracy is counted.

Through the real local HTTP stub server (scripted completions are fixtures); the plans here mostly
do not move the robot, so that each episode is cheap, while the reporter's code and the task
predicate judge the real MuJoCo scene.
"""

from __future__ import annotations

from typing import Any

import pytest

from capmj.bench.report import markdown
from capmj.bench.results import summarize
from llm_stub_server import StubLLMServer
from test_llm_chain import REPORTER, Router, agent, code, episode, lmp_of

JUDGE_FALSE = "judge = False\nreason = 'the blocks are not stacked'\nwrong = ['movable small cyan block with obj_id 3']"


def planner_sequence(*plans: str):
    """A planner handler answering ``plans`` in order (the last one repeatedly)."""
    answers = list(plans)

    def answer(request: dict[str, Any]) -> str:
        return code(answers.pop(0) if len(answers) > 1 else answers[0])

    return answer


def requests_of(server: StubLLMServer, lmp: str) -> list[dict[str, Any]]:
    return [r for r in server.requests if lmp_of(r) == lmp]


# ------------------------------------------------------------------------------------------------
# 1. a reporter that reaches a verdict
# ------------------------------------------------------------------------------------------------
def test_reporter_answer_missing_its_first_line_still_yields_a_verdict(server: StubLLMServer) -> None:
    first, rest = REPORTER.strip().split("\n", 1)
    assert first == "poses = get_obj_pos_dict()"
    server.respond_with(Router(planner=code("say('nothing to do')"), parse_completion=code(rest)))
    result = episode(agent(server, reporter="text"))
    (attempt,) = result.llm.attempts
    assert attempt.verdict is False and attempt.verdict_source == "code", attempt
    assert "0 of 5 blocks in the orange zone" in attempt.reason
    assert attempt.reporter_errors == () and attempt.predicate is False
    assert len(requests_of(server, "parse_completion")) == 1  # no repair was needed


def test_reporter_code_failing_twice_falls_back_to_a_direct_verdict(server: StubLLMServer) -> None:
    broken = "zone = 'fixed orange zone with obj_id 1'\nheight = poses[zone][0][2]\njudge = height > limit\n"
    server.respond_with(Router(planner=code("say('nothing to do')"), parse_completion=code(broken),
                               reporter_direct="Looking at the poses:\n" + code(JUDGE_FALSE)))
    result = episode(agent(server, reporter="text"))
    (attempt,) = result.llm.attempts
    assert attempt.verdict is False and attempt.verdict_source == "direct", attempt
    assert attempt.wrong == ("movable small cyan block with obj_id 3",)
    assert [e.split(":")[0] for e in attempt.reporter_errors] == ["code", "repair"]
    assert "name 'limit' is not defined" in attempt.reporter_errors[0]
    checks = requests_of(server, "parse_completion")
    assert len(checks) == 2
    repair = checks[1]["messages"][-1]["content"]  # the error and the failing line go back to the model
    assert "name 'limit' is not defined" in repair and "line 3: judge = height > limit" in repair
    direct = requests_of(server, "reporter_direct")[0]["messages"][-1]["content"]
    assert "movable small cyan block with obj_id 3: centre [" in direct and result.goal in direct
    assert attempt.predicate is False  # the direct verdict agreed with the predicate


def test_vlm_reporter_gets_the_same_fallback(server: StubLLMServer) -> None:
    server.respond_with(Router(planner=code("say('nothing to do')"), vlm_reporter="It looks done to me.",
                               reporter_direct=code(JUDGE_FALSE)))
    result = episode(agent(server, reporter="vlm"))
    (attempt,) = result.llm.attempts
    assert attempt.verdict is False and attempt.verdict_source == "direct", attempt
    vlm = requests_of(server, "vlm_reporter")
    if attempt.reporter_errors[0].startswith("code: no images"):
        assert vlm == []  # no OpenGL renderer here: straight to the direct verdict
    else:
        assert len(vlm) == 2 and "gave no verdict" in vlm[1]["messages"][-1]["content"]


# ------------------------------------------------------------------------------------------------
# 2. an unknown verdict is not success
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("policy", ["replan", "stop"])
def test_unknown_verdict_replans_or_stops(server: StubLLMServer, policy: str) -> None:
    server.respond_with(Router(planner=planner_sequence("say('plan one')", "say('plan two')"),
                               parse_completion="I am not sure.", reporter_direct="Hard to say."))
    result = episode(agent(server, reporter="text", attempts=2, on_unknown=policy))
    attempts = result.llm.attempts
    assert attempts[0].verdict is None and attempts[0].verdict_source == "unknown"
    assert attempts[0].on_unknown == policy and result.llm.on_unknown == policy
    if policy == "replan":
        assert len(attempts) == 2 and result.llm.stopped == "attempts used up"
        assert len(requests_of(server, "planner")) == 2
        replan = requests_of(server, "planner")[1]["messages"][-1]["content"]
        assert "goal UNKNOWN" in replan
    else:
        assert len(attempts) == 1 and result.llm.stopped == "reporter: unknown"
        assert len(requests_of(server, "planner")) == 1


# ------------------------------------------------------------------------------------------------
# 3. re-plans that differ
# ------------------------------------------------------------------------------------------------
def test_identical_replans_are_asked_again_hotter_with_deterministic_seeds(server: StubLLMServer) -> None:
    """Identical twice, then a different plan: 2 extra requests, temperatures rise, the new plan runs."""
    same, other = "say('plan A')", "# a new idea\nsay('plan B')"

    def run() -> tuple[Any, list[dict[str, Any]]]:
        server.reset()
        server.respond_with(Router(planner=planner_sequence(same, same, same, other),
                                   parse_completion=code(JUDGE_FALSE)))
        result = episode(agent(server, reporter="text", attempts=2, replan_temperature=0.4))
        return result, requests_of(server, "planner")

    result, planner = run()
    first, second = result.llm.attempts
    assert len(planner) == 4  # attempt 1, then attempt 2's request and its 2 retries
    assert [r["temperature"] for r in planner] == [0.0, 0.4, 0.7, 1.0]
    seeds = [r.get("seed") for r in planner]
    assert seeds[0] is None and all(isinstance(s, int) for s in seeds[1:]) and len(set(seeds[1:])) == 3
    assert (first.temperatures, first.seeds, first.extra_requests) == ((0.0,), (None,), 0)
    assert (second.temperatures, second.seeds, second.extra_requests) == ((0.4, 0.7, 1.0), tuple(seeds[1:]), 2)
    assert (second.code_differs, second.identical_to, second.not_run) == (True, None, None)
    assert second.said == ("plan B",) and "plan B" in second.code  # the different plan ran
    # the first retry shows the failure again in the conversation and asks for changed lines
    text = planner[2]["messages"][-1]["content"]
    assert "identical to the plan of attempt 1" in text and "the blocks are not stacked" in text
    assert "change at least the lines that caused the failure of attempt 1" in text
    assert planner[2]["messages"][-2] == {"role": "assistant", "content": code(same)}
    assert len(planner[2]["messages"]) == len(planner[1]["messages"]) + 2
    # the second starts afresh: the planner prompt, the goal and the failure, but no plan to copy
    fresh = planner[3]["messages"]
    assert len(fresh) == len(planner[0]["messages"]) and fresh[0] == planner[0]["messages"][0]
    assert "say('plan A')" not in str(fresh) and "the blocks are not stacked" in fresh[-1]["content"]
    assert "An earlier plan for this goal (attempt 1) did not achieve it" in fresh[-1]["content"]
    # the same episode asks with the same seeds again (reproducible where the server honours seed)
    _, again = run()
    assert [r.get("seed") for r in again] == seeds and [r["temperature"] for r in again] == [0.0, 0.4, 0.7, 1.0]


def test_plan_still_identical_after_the_retries_is_not_run(server: StubLLMServer) -> None:
    """Every answer is plan A: attempt 2 is recorded as not re-run; the scene ends where plan A ended."""
    block = "movable small cyan block with obj_id 3"
    plan_a = f"put_first_on_second('{block}', 'fixed orange zone with obj_id 1')\nsay('plan A ran')"
    server.respond_with(Router(planner=code(plan_a), parse_completion=code(JUDGE_FALSE)))
    result = episode(agent(server, reporter="text", attempts=2, replan_temperature=0.7, replan_retries=2))
    first, second = result.llm.attempts
    planner = requests_of(server, "planner")
    assert len(planner) == 4 and [r["temperature"] for r in planner] == [0.0, 0.7, 1.0, 1.3]
    assert first.primitives == 1 and first.said == ("plan A ran",) and first.predicate_progress > 0
    assert second.not_run == "identical to attempt 1 after 2 retries; not re-run"
    assert (second.code_differs, second.identical_to, second.extra_requests) == (False, 1, 2)
    assert second.error is None and second.verdict_source is None  # failed, but neither raised nor judged
    assert second.primitives == 0 and second.said == () and second.api_calls == 0  # the sandbox never ran it
    assert "put_first_on_second" in second.code and second.report == f"plan not run: {second.not_run}"
    assert len(requests_of(server, "parse_completion")) == 1  # only attempt 1 was judged
    assert result.llm.stopped == "attempts used up" and result.error is None
    # the episode ends where plan A ended (as re-running it from the reset scene would), not in the initial scene
    assert result.progress == first.predicate_progress and result.primitives == 1


def test_attempt_after_a_plan_not_run_replans_from_the_last_plan_that_ran(server: StubLLMServer) -> None:
    same, other = "say('plan A')", "say('plan C')"
    server.respond_with(Router(planner=planner_sequence(same, same, same, same, other),
                               parse_completion=code(JUDGE_FALSE)))
    result = episode(agent(server, reporter="text", attempts=3, replan_retries=1))
    first, second, third = result.llm.attempts
    planner = requests_of(server, "planner")
    assert len(planner) == 5  # 1 + (1 + 1 retry, not run) + (1 + 1 retry)
    assert second.not_run == "identical to attempt 1 after 1 retries; not re-run"
    assert (third.not_run, third.code_differs, third.extra_requests, third.said) == (None, True, 1, ("plan C",))
    # attempt 3 is shown attempt 1's plan and failure, and samples with seeds of its own
    assert planner[3]["messages"][-1]["content"] == planner[1]["messages"][-1]["content"]
    assert "(attempt 1) ran from the initial scene" in planner[3]["messages"][-1]["content"]
    assert len({r["seed"] for r in planner[1:]}) == 4
    assert [r["temperature"] for r in planner] == [0.0, 0.7, 1.0, 0.7, 1.0]
    assert (second.code_differs, third.identical_to) == (False, None)


def test_replan_sampling_schedule() -> None:
    from capmj.agents.llm_agent.planner import MAX_REPLAN_TEMPERATURE, replan_sampling

    assert [replan_sampling(0.7, 10001, 2, r).temperature for r in range(5)] == [0.7, 1.0, 1.3, 1.5, 1.5]
    assert replan_sampling(0.0, 10001, 2, 1).temperature == 0.3
    assert replan_sampling(1.8, 10001, 2, 3).temperature == 1.8 > MAX_REPLAN_TEMPERATURE  # never below the base
    seeds = {replan_sampling(0.7, s, k, r).seed for s in (10001, 10003) for k in (2, 3) for r in range(4)}
    assert len(seeds) == 16 and all(0 <= s < 2**31 for s in seeds)
    assert replan_sampling(0.7, 10001, 2, 1) == replan_sampling(0.7, 10001, 2, 1)


def test_replan_prompt_shows_the_numbered_plan_and_the_failing_line(server: StubLLMServer) -> None:
    failing = "blocks = get_obj_names()\nn = len(blocks)\nz = get_obj_pos('the purple thing')\nsay(n)"
    server.respond_with(Router(planner=planner_sequence(failing, "say('fixed')")))
    result = episode(agent(server, attempts=2))
    first, second = result.llm.attempts
    assert first.error_line == 3 and "unknown object" in first.error
    replan = requests_of(server, "planner")[1]["messages"]
    assert replan[2] == {"role": "assistant", "content": code(failing)}
    text = replan[-1]["content"]
    for i, line in enumerate(failing.splitlines(), start=1):
        assert f"# {i}| {line}" in text
    assert "# It failed at line 3: z = get_obj_pos('the purple thing')" in text
    assert "unknown object" in text and "Write a corrected complete plan" in text
    assert second.error is None and second.code_differs is True


# ------------------------------------------------------------------------------------------------
# 4. the reporter's accuracy as a result
# ------------------------------------------------------------------------------------------------
def _attempt(k: int, verdict: bool | None, predicate: bool | None, source: str | None = "code",
             differs: bool | None = None) -> dict[str, Any]:
    return {"attempt": k, "verdict": verdict, "predicate": predicate, "verdict_source": source,
            "code_differs": differs, "on_unknown": "replan" if source == "unknown" else None,
            "extra_requests": 2 if differs is False else 0, "not_run": None}


def _episode(task: str, seed: int, success: bool, attempts: list[dict[str, Any]], tokens: int) -> dict[str, Any]:
    return {"task": task, "seed": seed, "agent": "llm", "model": "m", "success": success, "progress": 0.0,
            "primitives": 0, "wall_s": 1.0, "error": None, "rrd": None,
            "llm": {"attempts": attempts, "prompt_tokens": tokens, "completion_tokens": 10}}


def test_reporter_agreement_counts_match_hand_made_outcomes() -> None:
    records = [
        # A: verdict True but predicate False (false positive), stops
        _episode("A", 1, False, [_attempt(1, True, False)], 100),
        # A: false negative, then a changed plan judged right
        _episode("A", 3, True, [_attempt(1, False, True), _attempt(2, True, True, differs=True)], 200),
        # B: the plan raised (not judged), then unknown, then an identical plan judged right (False/False)
        _episode("B", 1, False, [_attempt(1, None, False, source=None), _attempt(2, None, False, "unknown", True),
                                 _attempt(3, False, False, "direct", False)], 300),
    ]
    summary = summarize(records)
    a, b = summary["tasks"]["A"]["llm m"]["loop"], summary["tasks"]["B"]["llm m"]["loop"]
    overall = summary["overall"]["llm m"]["loop"]
    assert (a["compared"], a["agree"], a["false_positives"], a["false_negatives"]) == (3, 1, 1, 1)
    assert (b["compared"], b["agree"], b["false_positives"], b["false_negatives"]) == (1, 1, 0, 0)
    assert (b["reporter_runs"], b["verdicts"], b["verdict_rate"]) == (2, 1, 0.5)
    assert b["verdict_sources"] == {"code": 0, "repair": 0, "direct": 1, "unknown": 1}
    assert (b["replans"], b["identical_replans"], b["identical_replan_rate"]) == (2, 1, 0.5)
    assert overall["agree"] == 2 and overall["compared"] == 4 and overall["agreement"] == 0.5
    assert overall["verdicts"] == 4 and overall["reporter_runs"] == 5
    assert (overall["replans"], overall["identical_replans"]) == (3, 1)
    assert overall["mean_attempts"] == 2.0 and overall["mean_tokens"] == (600 + 30) / 3
    assert summary["overall"]["llm m"]["successes"] == 1
    md = markdown(summary)
    assert "## Closed loop" in md
    assert (overall["not_rerun"], overall["extra_requests"]) == (0, 2)
    assert ("| **Overall** | llm m | 1/3 (33 %) | 2.00 | 4/5 (80 %) | 3/0/1/1 | 2/4 (50 %) | 1 | 1 | 1/3 (33 %) | 0 | 2 "
            "| 210 |") in md
    # non-LLM results have no closed-loop statistics and no table
    oracle = [{**r, "agent": "oracle", "model": None, "llm": {}} for r in records]
    assert "loop" not in summarize(oracle)["overall"]["oracle"] and "Closed loop" not in markdown(summarize(oracle))


def test_plans_not_rerun_and_extra_requests_are_counted() -> None:
    not_run = {**_attempt(2, None, None, source=None, differs=False), "extra_requests": 3,
               "not_run": "identical to attempt 1 after 3 retries; not re-run"}
    old = {**_attempt(2, False, False, differs=True), "extra_request": True}  # a record from before retries
    del old["extra_requests"], old["not_run"]
    records = [_episode("A", 1, False, [_attempt(1, False, False), not_run], 100),
               _episode("A", 3, False, [_attempt(1, False, False), old], 100)]
    loop = summarize(records)["overall"]["llm m"]["loop"]
    assert (loop["replans"], loop["identical_replans"], loop["not_rerun"], loop["extra_requests"]) == (2, 1, 1, 4)
    assert loop["reporter_runs"] == 3  # the plan not run was not judged
    assert "| 1/2 (50 %) | 1 | 4 | 110 |" in markdown(summarize(records))


def test_loop_options_reach_the_agent_and_bad_ones_are_rejected() -> None:
    from capmj.agents.factory import make_agent
    from capmj.agents.llm_agent.options import LLMAgentOptions
    from capmj.bench.cli import build_parser
    from capmj.errors import ConfigError

    args = build_parser().parse_args(["--agent", "llm", "--on-unknown", "stop", "--replan-temperature", "0.3"])
    a = make_agent("llm", model="m", on_unknown=args.on_unknown, replan_temperature=args.replan_temperature)
    assert a.options.on_unknown == "stop" and a.options.replan_temperature == 0.3 and a.config.temperature == 0.0
    default = LLMAgentOptions()
    assert default.on_unknown == "replan" and default.replan_temperature > 0 and default.replan_retries == 3
    args = build_parser().parse_args(["--agent", "llm", "--replan-retries", "0"])
    assert make_agent("llm", model="m", replan_retries=args.replan_retries).options.replan_retries == 0
    for bad in (-1, 11, 1.5, True, "2"):
        with pytest.raises(ConfigError, match=r"replan_retries \(--replan-retries\) must be an integer from 0 to 10"):
            LLMAgentOptions(replan_retries=bad)
    with pytest.raises(ConfigError, match="replan, stop"):
        make_agent("llm", model="m", on_unknown="ignore")
    with pytest.raises(ConfigError, match=">= 0"):
        LLMAgentOptions(replan_temperature=-1)
    with pytest.raises(SystemExit):
        build_parser().parse_args(["--on-unknown", "success"])


@pytest.mark.parametrize("value", ["-1", "11"])
def test_bad_replan_retries_flag_is_a_one_line_error_before_anything_runs(value: str, tmp_path: Any,
                                                                          capsys: pytest.CaptureFixture[str]) -> None:
    from capmj.bench.cli import main

    out = tmp_path / "run"
    rc = main(["--agent", "llm", "--model", "openai/stub", "--api-base", "http://127.0.0.1:9/v1",
               "--tasks", "stack-all-blocks-on-a-zone", "--seeds", "10001", "--replan-retries", value,
               "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2
    assert "capmj-bench: error: replan_retries (--replan-retries) must be an integer from 0 to 10" in err
    assert f"got {value}" in err and not out.exists()
