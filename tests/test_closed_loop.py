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
    (attempt,) = result.llm["attempts"]
    assert attempt["verdict"] is False and attempt["verdict_source"] == "code", attempt
    assert "0 of 5 blocks in the orange zone" in attempt["reason"]
    assert attempt["reporter_errors"] == [] and attempt["predicate"] is False
    assert len(requests_of(server, "parse_completion")) == 1  # no repair was needed


def test_reporter_code_failing_twice_falls_back_to_a_direct_verdict(server: StubLLMServer) -> None:
    broken = "zone = 'fixed orange zone with obj_id 1'\nheight = poses[zone][0][2]\njudge = height > limit\n"
    server.respond_with(Router(planner=code("say('nothing to do')"), parse_completion=code(broken),
                               reporter_direct="Looking at the poses:\n" + code(JUDGE_FALSE)))
    result = episode(agent(server, reporter="text"))
    (attempt,) = result.llm["attempts"]
    assert attempt["verdict"] is False and attempt["verdict_source"] == "direct", attempt
    assert attempt["wrong"] == ["movable small cyan block with obj_id 3"]
    assert [e.split(":")[0] for e in attempt["reporter_errors"]] == ["code", "repair"]
    assert "name 'limit' is not defined" in attempt["reporter_errors"][0]
    checks = requests_of(server, "parse_completion")
    assert len(checks) == 2
    repair = checks[1]["messages"][-1]["content"]  # the error and the failing line go back to the model
    assert "name 'limit' is not defined" in repair and "line 3: judge = height > limit" in repair
    direct = requests_of(server, "reporter_direct")[0]["messages"][-1]["content"]
    assert "movable small cyan block with obj_id 3: centre [" in direct and result.goal in direct
    assert attempt["predicate"] is False  # the direct verdict agreed with the predicate


def test_vlm_reporter_gets_the_same_fallback(server: StubLLMServer) -> None:
    server.respond_with(Router(planner=code("say('nothing to do')"), vlm_reporter="It looks done to me.",
                               reporter_direct=code(JUDGE_FALSE)))
    result = episode(agent(server, reporter="vlm"))
    (attempt,) = result.llm["attempts"]
    assert attempt["verdict"] is False and attempt["verdict_source"] == "direct", attempt
    vlm = requests_of(server, "vlm_reporter")
    if attempt["reporter_errors"][0].startswith("code: no images"):
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
    attempts = result.llm["attempts"]
    assert attempts[0]["verdict"] is None and attempts[0]["verdict_source"] == "unknown"
    assert attempts[0]["on_unknown"] == policy and result.llm["on_unknown"] == policy
    if policy == "replan":
        assert len(attempts) == 2 and result.llm["stopped"] == "attempts used up"
        assert len(requests_of(server, "planner")) == 2
        replan = requests_of(server, "planner")[1]["messages"][-1]["content"]
        assert "goal UNKNOWN" in replan
    else:
        assert len(attempts) == 1 and result.llm["stopped"] == "reporter: unknown"
        assert len(requests_of(server, "planner")) == 1


# ------------------------------------------------------------------------------------------------
# 3. re-plans that differ
# ------------------------------------------------------------------------------------------------
def test_identical_replan_triggers_one_extra_request(server: StubLLMServer) -> None:
    same, other = "say('plan A')", "# a new idea\nsay('plan B')"
    server.respond_with(Router(planner=planner_sequence(same, same, other, other, other),
                               parse_completion=code(JUDGE_FALSE)))
    result = episode(agent(server, reporter="text", attempts=3, replan_temperature=0.4))
    first, second, third = result.llm["attempts"]
    planner = requests_of(server, "planner")
    assert len(planner) == 5  # 1 + (1 + extra) + (1 + extra)
    assert [r["temperature"] for r in planner] == [0.0, 0.4, 0.4, 0.4, 0.4]
    assert "identical to the plan of attempt 1" in planner[2]["messages"][-1]["content"]
    assert (first["code_differs"], first["extra_request"]) == (None, False)
    assert (second["code_differs"], second["identical_to"], second["extra_request"]) == (True, None, True)
    # the model insisted on plan B in attempt 3: asked once more only, then recorded as identical
    assert (third["code_differs"], third["identical_to"], third["extra_request"]) == (False, 2, True)
    assert "identical to the plan of attempt 2" in planner[4]["messages"][-1]["content"]
    # the reporter's reason and wrong objects went into the re-plan request
    replan = planner[1]["messages"][-1]["content"]
    assert "the blocks are not stacked" in replan and "objects whose state is wrong" in replan
    assert "movable small cyan block with obj_id 3" in replan


def test_replan_prompt_shows_the_numbered_plan_and_the_failing_line(server: StubLLMServer) -> None:
    failing = "blocks = get_obj_names()\nn = len(blocks)\nz = get_obj_pos('the purple thing')\nsay(n)"
    server.respond_with(Router(planner=planner_sequence(failing, "say('fixed')")))
    result = episode(agent(server, attempts=2))
    first, second = result.llm["attempts"]
    assert first["error_line"] == 3 and "unknown object" in first["error"]
    replan = requests_of(server, "planner")[1]["messages"]
    assert replan[2] == {"role": "assistant", "content": code(failing)}
    text = replan[-1]["content"]
    for i, line in enumerate(failing.splitlines(), start=1):
        assert f"# {i}| {line}" in text
    assert "# It failed at line 3: z = get_obj_pos('the purple thing')" in text
    assert "unknown object" in text and "Write a corrected complete plan" in text
    assert second["error"] is None and second["code_differs"] is True


# ------------------------------------------------------------------------------------------------
# 4. the reporter's accuracy as a result
# ------------------------------------------------------------------------------------------------
def _attempt(k: int, verdict: bool | None, predicate: bool | None, source: str | None = "code",
             differs: bool | None = None) -> dict[str, Any]:
    return {"attempt": k, "verdict": verdict, "predicate": predicate, "verdict_source": source,
            "code_differs": differs, "on_unknown": "replan" if source == "unknown" else None,
            "extra_request": differs is False}


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
    assert "| **Overall** | llm m | 1/3 (33 %) | 2.00 | 4/5 (80 %) | 3/0/1/1 | 2/4 (50 %) | 1 | 1 | 1/3 (33 %) | 210 |" in md
    # non-LLM results have no closed-loop statistics and no table
    oracle = [{**r, "agent": "oracle", "model": None, "llm": {}} for r in records]
    assert "loop" not in summarize(oracle)["overall"]["oracle"] and "Closed loop" not in markdown(summarize(oracle))


def test_loop_options_reach_the_agent_and_bad_ones_are_rejected() -> None:
    from capmj.agents.factory import make_agent
    from capmj.agents.llm_agent import LLMAgent
    from capmj.bench.cli import build_parser
    from capmj.errors import ConfigError

    args = build_parser().parse_args(["--agent", "llm", "--on-unknown", "stop", "--replan-temperature", "0.3"])
    a = make_agent("llm", model="m", on_unknown=args.on_unknown, replan_temperature=args.replan_temperature)
    assert a.on_unknown == "stop" and a.replan_config.temperature == 0.3 and a.config.temperature == 0.0
    assert LLMAgent("m").on_unknown == "replan" and LLMAgent("m").replan_config.temperature > 0
    with pytest.raises(ConfigError, match="replan, stop"):
        LLMAgent("m", on_unknown="ignore")
    with pytest.raises(ConfigError, match=">= 0"):
        LLMAgent("m", replan_temperature=-1)
    with pytest.raises(SystemExit):
        build_parser().parse_args(["--on-unknown", "success"])
