"""The loop policies (issue #26 item 3): ``thesis`` as before, ``careful`` judging a raising plan's
state, re-planning from the current state on a partial verdict, stopping on a low-confidence one.

Episodes run in real MuJoCo through the real local HTTP stub server; the scripted completions are
fixtures (plans that move real blocks, reporter answers that read the facts in their prompt).
"""

from __future__ import annotations

import itertools
import re
from typing import Any

import pytest

from capmj.agents.report.confidence import Assessment
from capmj.agents.llm_agent.loop_policy import Outcome, decide
from capmj.errors import ConfigError
from capmj.records import LOOP_RULES
from llm_stub_server import StubLLMServer, prompt_text
from test_llm_chain import REPORTER, Router, agent, code, episode, lmp_of

BLOCKS = "[n for n in get_obj_names() if ' block ' in n]"
ZONE = "'fixed orange zone with obj_id 1'"
ALL_THEN_RAISE = f"""
for block in {BLOCKS}:
    put_first_on_second(block, {ZONE})
copied = [][0]  # went on copying the prompt's examples
"""
THREE = f"for block in {BLOCKS}[:3]:\n    put_first_on_second(block, {ZONE})"
REST = f"for block in {BLOCKS}[3:]:\n    put_first_on_second(block, {ZONE})"
NOTHING = "say('nothing to do')"


def planner(*plans: str):
    answers = list(plans)
    return lambda request: code(answers.pop(0) if len(answers) > 1 else answers[0])


def from_facts(request: dict[str, Any]) -> str:
    """A checked-prompt answer: failed, naming the blocks whose facts say they are in no zone."""
    loose = re.findall(r"^- (movable [^:]+ block with obj_id \d+): .*in no zone or bowl", prompt_text(request), re.M)
    if loose:
        return code(f"judge = False\nreason = 'blocks outside the zone'\nwrong = {loose!r}")
    return code("judge = True\nreason = 'every block is in the orange zone'\nwrong = []")


def requests_of(server: StubLLMServer, lmp: str) -> list[dict[str, Any]]:
    return [r for r in server.requests if lmp_of(r) == lmp]


def run(server: StubLLMServer, policy: str, *plans: str, **kw: Any):
    server.respond_with(Router(planner=planner(*plans), reporter_checked=kw.pop("reporter", from_facts),
                               parse_completion=code(REPORTER)))
    kw.setdefault("reporter_prompt", "checked")
    return episode(agent(server, reporter="text", attempts=kw.pop("attempts", 2), loop_policy=policy, **kw))


# ------------------------------------------------------------------------------------------------
# (a) a plan that reaches the goal and then raises
# ------------------------------------------------------------------------------------------------
def test_a_plan_that_reaches_the_goal_then_raises_ends_achieved_under_careful(server: StubLLMServer) -> None:
    result = run(server, "careful", ALL_THEN_RAISE, NOTHING)
    (first,) = result.llm.attempts
    assert first.error is not None and "IndexError" in first.error and first.error_line == 3
    assert first.verdict is True and first.confidence == "high" and first.rule == "achieved_after_error"
    assert result.llm.stopped == "reporter: achieved after an error" and result.llm.loop_policy == "careful"
    assert result.success and result.error is None and result.primitives == 5  # state kept, no reset
    assert len(requests_of(server, "planner")) == 1


def test_the_thesis_loop_resets_that_plan_without_judging_it(server: StubLLMServer) -> None:
    result = run(server, "thesis", ALL_THEN_RAISE, NOTHING)
    first, second = result.llm.attempts
    assert first.error is not None and first.verdict is None and first.verdict_source is None
    assert first.rule == "error" and second.reset is True and second.primitives == 0
    assert requests_of(server, "reporter_checked") and not result.success  # the reached goal was undone


def test_careful_judges_only_plans_that_acted(server: StubLLMServer) -> None:
    result = run(server, "careful", "copied = [][0]", THREE + "\n" + REST, attempts=2)
    first, second = result.llm.attempts
    assert first.error is not None and first.primitives == 0 and first.verdict is None and first.rule == "error"
    assert second.reset is True and second.rule == "achieved" and result.success


# ------------------------------------------------------------------------------------------------
# (b) a partial verdict re-plans from the current state
# ------------------------------------------------------------------------------------------------
def test_a_partial_verdict_replans_without_reset_under_careful(server: StubLLMServer) -> None:
    result = run(server, "careful", THREE, REST)
    first, second = result.llm.attempts
    assert first.verdict is False and len(first.wrong) == 2 and first.confidence == "high"
    assert first.rule == "partial_replan" and second.reset is False and second.rule == "achieved"
    assert (first.primitives, second.primitives) == (3, 2) and result.success  # the three placed blocks stayed
    replan = requests_of(server, "planner")[1]["messages"][-1]["content"]
    assert "The scene has NOT been reset" in replan and "has been reset to its initial state" not in replan
    assert first.wrong[0] in replan  # told which objects are wrong


def test_a_plan_run_from_a_kept_scene_is_no_repeat_for_an_attempt_from_the_initial_scene(
        server: StubLLMServer) -> None:
    """Attempt 2 keeps the scene and raises before acting (so attempt 3 resets); attempt 3 answers
    the same plan: from the initial scene its outcome is unknown, so it runs, not "identical"."""
    result = run(server, "careful", THREE, "copied = [][0]", attempts=3)
    first, second, third = result.llm.attempts
    assert (first.rule, second.reset, second.rule) == ("partial_replan", False, "error")
    assert third.reset is True and third.not_run is None and third.identical_to is None
    assert third.extra_requests == 0 and third.error is not None  # it ran (and raised again)


def test_the_same_verdict_resets_under_thesis(server: StubLLMServer) -> None:
    result = run(server, "thesis", THREE, REST)
    first, second = result.llm.attempts
    assert first.rule == "not_achieved" and second.reset is True and not result.success
    assert "has been reset to its initial state" in requests_of(server, "planner")[1]["messages"][-1]["content"]


def test_a_verdict_naming_every_movable_object_resets_under_careful(server: StubLLMServer) -> None:
    result = run(server, "careful", NOTHING, THREE + "\n" + REST)
    first, second = result.llm.attempts
    assert first.verdict is False and len(first.wrong) == 5 and first.rule == "not_achieved"
    assert second.reset is True and result.success


# ------------------------------------------------------------------------------------------------
# (c) a low-confidence verdict keeps the state
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("answer, why", [
    (code("judge = False\nreason = 'not sure'\nwrong = []"), "names_nothing"),
    (code("judge = False\nreason = 'hmm'\nwrong = ['the purple elephant']"), "names_no_real_object"),
    (code("judge = False\nreason = 'zone'\nwrong = ['fixed purple zone with obj_id 2']"), "names_only_fixed"),
    ("I cannot tell.", "no_verdict"),
])
def test_a_low_confidence_verdict_stops_and_keeps_the_state_under_careful(server: StubLLMServer, answer: str,
                                                                          why: str) -> None:
    result = run(server, "careful", THREE, REST, reporter=answer, on_unknown="replan")
    (first,) = result.llm.attempts
    assert (first.confidence, first.low_confidence, first.rule) == ("low", why, "low_confidence_stop")
    assert result.llm.stopped == "reporter: low confidence" and result.primitives == 3
    assert first.on_unknown is None and len(requests_of(server, "planner")) == 1
    thesis = run(server, "thesis", THREE, REST, reporter=answer, on_unknown="replan")
    assert thesis.llm.attempts[0].rule == ("unknown_replan" if why == "no_verdict" else "not_achieved")
    assert len(thesis.llm.attempts) == 2 and thesis.llm.attempts[1].reset is True


def test_after_an_error_a_low_confidence_verdict_resets_as_the_thesis_does(server: StubLLMServer) -> None:
    no = code("judge = False\nreason = 'not sure'\nwrong = []")
    result = run(server, "careful", THREE + "\ncopied = [][0]", THREE + "\n" + REST, reporter=no, attempts=2)
    first, second = result.llm.attempts
    assert first.error is not None and first.verdict is False and first.confidence == "low"
    assert first.rule == "error" and second.reset is True
    told = requests_of(server, "planner")[1]["messages"]
    assert "not sure" not in str(told)  # the unfounded verdict is not passed on ...
    server.reset()
    server.respond_with(Router(planner=planner(THREE + "\ncopied = [][0]", THREE + "\n" + REST)))
    episode(agent(server, reporter="none", attempts=2, loop_policy="careful"))
    assert requests_of(server, "planner")[1]["messages"] == told  # ... the re-plan is the reporter-less loop's


def test_after_an_error_a_high_confidence_verdict_is_passed_on(server: StubLLMServer) -> None:
    def every_block_wrong(request: dict[str, Any]) -> str:
        blocks = sorted(set(re.findall(r"movable [^:\n]+ block with obj_id \d+", prompt_text(request))))
        return code(f"judge = False\nreason = 'no block is where it belongs'\nwrong = {blocks!r}")

    result = run(server, "careful", THREE + "\ncopied = [][0]", THREE + "\n" + REST, reporter=every_block_wrong)
    first = result.llm.attempts[0]
    assert (first.rule, first.confidence) == ("error", "high")
    assert "no block is where it belongs" in str(requests_of(server, "planner")[1]["messages"])


# ------------------------------------------------------------------------------------------------
# the decision table
# ------------------------------------------------------------------------------------------------
def _old_thesis_stops(o: Outcome, on_unknown: str) -> bool:
    """The thesis loop's stop test as it was written before policies existed (llm_agent.act)."""
    unknown = not o.error and o.judged and o.verdict is None
    failed = o.not_run or o.error or (o.judged and o.verdict is False) or (unknown and on_unknown == "replan")
    return not failed


def test_thesis_decisions_equal_the_old_loop_on_every_outcome() -> None:
    for not_run, error, judged, verdict, conf, share, on_unknown in itertools.product(
            (False, True), (False, True), (False, True), (None, True, False), ("high", "low"), (0.4, 1.0),
            ("replan", "stop")):
        if (not_run and (error or judged)) or (error and judged) or (not judged and verdict is not None):
            continue  # outcomes the thesis loop cannot produce (it never judges a raising plan)
        o = Outcome(not_run=not_run, error=error, verdict=verdict, judged=judged,
                    assessment=Assessment(conf) if judged else None, wrong_share=share)
        d = decide("thesis", o, on_unknown=on_unknown)
        assert d.stop is _old_thesis_stops(o, on_unknown) and d.reset is True and d.rule in LOOP_RULES, (o, d)


def test_careful_rules_fire_only_where_they_should() -> None:
    high, low = Assessment("high"), Assessment("low", "names_nothing")
    assert decide("careful", Outcome(error=True, judged=True, verdict=True, assessment=high)).rule == \
        "achieved_after_error"
    assert decide("careful", Outcome(error=True, judged=True, verdict=True, assessment=low)).rule == "error"
    assert decide("careful", Outcome(error=True)).rule == "error"
    assert decide("careful", Outcome(error=True, judged=True, verdict=False, assessment=low)).shows_report is False
    assert decide("thesis", Outcome(error=True, judged=True, verdict=False, assessment=low)).shows_report is True
    d = decide("careful", Outcome(judged=True, verdict=False, assessment=high, wrong_share=0.5))
    assert (d.rule, d.stop, d.reset) == ("partial_replan", False, False)
    assert decide("careful", Outcome(judged=True, verdict=False, assessment=high, wrong_share=1.0)).rule == \
        "not_achieved"
    assert decide("careful", Outcome(judged=True, verdict=False, assessment=low)).rule == "low_confidence_stop"
    assert decide("careful", Outcome(judged=True, verdict=True, assessment=high)).rule == "achieved"
    assert decide("careful", Outcome()).rule == "finished"  # no reporter: as the thesis
    assert decide("careful", Outcome(not_run=True), reset=False).reset is False
    assert decide("thesis", Outcome(not_run=True), reset=False).reset is True


def test_bad_policies_are_refused_and_the_options_reach_the_agent() -> None:
    from capmj.agents.factory import make_agent
    from capmj.agents.llm_agent.options import LLMAgentOptions
    from capmj.agents.choices import LOOP_POLICIES, ON_UNKNOWN, REPORTER_PROMPTS, REPORTERS
    from capmj.agents.report.registry import make_reporter
    from capmj.bench.cli import build_parser

    with pytest.raises(ConfigError, match="thesis, careful"):
        LLMAgentOptions(loop_policy="bold")
    with pytest.raises(ConfigError, match="needs --reporter text"):
        make_agent("llm", model="m", reporter="vlm", reporter_prompt="checked")
    args = build_parser().parse_args(["--agent", "llm", "--loop-policy", "careful", "--reporter-prompt", "checked"])
    a = make_agent("llm", model="m", reporter="text", loop_policy=args.loop_policy,
                   reporter_prompt=args.reporter_prompt)
    assert (a.options.loop_policy, a.options.reporter_prompt) == ("careful", "checked")
    assert (LLMAgentOptions().loop_policy, LLMAgentOptions().reporter_prompt) == ("thesis", "thesis")
    # every name the parser offers (capmj.agents.choices) is one the agent builds, each a reporter of its own
    actions = {a.dest: a.choices for a in build_parser()._actions}
    assert tuple(actions["loop_policy"]) == LOOP_POLICIES and tuple(actions["reporter_prompt"]) == REPORTER_PROMPTS
    for policy in LOOP_POLICIES:
        assert LLMAgentOptions(loop_policy=policy).loop_policy == policy
    for mode in REPORTERS:
        assert (make_reporter(mode) is None) == (mode == "none")
    assert len({type(make_reporter("text", None, p)) for p in REPORTER_PROMPTS}) == len(REPORTER_PROMPTS)
    for choice in ON_UNKNOWN:
        assert LLMAgentOptions(on_unknown=choice).on_unknown == choice
