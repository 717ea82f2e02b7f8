"""A plan that checks itself and starts over, as CapRavens' planner examples do: ``reset()`` and
``parse_completion(...)`` called from plan code.

On real MuJoCo worlds; the LLM end-to-end test goes through the scripted HTTP server
(tests/llm_stub_server.py), whose answers are fixtures: the reporter's checking code it returns is
real code judging the real scene, so the verdicts below come from physics, not from the script.
Written from capmj's docs; no example of the original is copied here.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.base import Budget, EpisodeContext
from capmj.agents.lmp.session import LMPSession
from capmj.agents.sandbox import run_code
from capmj.errors import BudgetExceeded, PlanError
from capmj.runner import run_episode
from capmj.sim.world import World
from capmj.tasks.protocol import make_scene
from capmj.tasks.registry import get_task
from test_llm_chain import MemoryRecorder, Router, agent, code

TASK = "stack-all-blocks-on-a-zone"
SEED = 10001  # orange zone 1 (target), purple zone 2, blocks 3..7
ORANGE, PURPLE = "fixed orange zone with obj_id 1", "fixed purple zone with obj_id 2"
CYAN = "movable small cyan block with obj_id 3"


def make_ctx(budget: Budget | None = None, recorder: Any = None) -> EpisodeContext:
    task = get_task(TASK)
    scene = make_scene(task, SEED)
    world = World(scene.objects)
    world.settle()
    return EpisodeContext(task, SEED, scene, world, budget=budget, recorder=recorder)


def physics(world: World) -> np.ndarray:
    snap = world.snapshot()
    return np.concatenate([snap.physics, snap.eq_data.ravel()])


# ------------------------------------------------------------------------------------------------
# reset() in a plan
# ------------------------------------------------------------------------------------------------
def test_reset_in_a_plan_restores_the_initial_scene_exactly_and_is_recorded() -> None:
    rec = MemoryRecorder()
    ctx = make_ctx(recorder=rec)
    initial = physics(ctx.world)
    api = PlannerAPI(ctx)
    start = api.functions()["get_obj_pos"](CYAN)
    ns = run_code(f"put_first_on_second({CYAN!r}, {PURPLE!r})\nmoved = get_obj_pos({CYAN!r})\nreset()\n"
                  f"back = get_obj_pos({CYAN!r})\nput_first_on_second({CYAN!r}, {ORANGE!r})\n",
                  api.functions())
    calls = [e["fn"] for e in api.call_log][1:]  # after the get_obj_pos of `start`
    assert calls == ["put_first_on_second", "get_obj_pos", "reset", "get_obj_pos", "put_first_on_second"]
    moved, back = np.array(ns["moved"], float), np.array(ns["back"], float)
    assert np.linalg.norm(moved[:2] - np.array(start[:2])) > 0.05  # the first put really moved it
    # and reset() brought it back (to 1e-5: `start` is the pose mj_step computed before its last
    # integration, `back` the restored state's own; the state itself is compared bit-exact below)
    assert np.allclose(back, start, atol=1e-5)
    assert "initial state" in rec.texts["planner/reset"][0]
    assert ctx.attempt == 0 and ctx.attempt_primitives == 2  # the same attempt; nothing refunded
    assert ctx.verdict().success is False  # one block on the orange zone is not all five

    ctx2 = make_ctx()
    run_code(f"put_first_on_second({CYAN!r}, {PURPLE!r})\nreset()\n", PlannerAPI(ctx2).functions())
    assert np.array_equal(physics(ctx2.world)[: len(initial)], initial)  # bit-exact, like the loop's reset


def test_reset_keeps_the_attempts_step_budget() -> None:
    """Steps spent before a reset still count, though the world's step counter goes back."""
    ctx = make_ctx(Budget(max_sim_steps=ctx_steps_for_one_put() + 200))
    f = PlannerAPI(ctx).functions()
    f["put_first_on_second"](CYAN, PURPLE)
    f["reset"]()
    f["put_first_on_second"](CYAN, ORANGE)  # within the budget: spent < one put + 200 steps
    with pytest.raises(BudgetExceeded, match="simulation budget"):
        f["put_first_on_second"](CYAN, PURPLE)  # without the carry, only one put would have been spent


def ctx_steps_for_one_put() -> int:
    ctx = make_ctx()
    before = ctx.world.steps
    PlannerAPI(ctx).functions()["put_first_on_second"](CYAN, PURPLE)
    return ctx.world.steps - before


def test_helper_code_cannot_reset_and_is_told_why() -> None:
    ctx = make_ctx()
    api = PlannerAPI(ctx)
    session = LMPSession(complete=lambda *a, **k: None, api=api.functions(), objects_text=api.objects_text)
    assert "reset" in session.plan_env() and "reset" not in session.helper_env()
    with pytest.raises(PlanError, match=r"reset\(\) cannot be called in the helper: it restores the episode's initial"):
        session.prepare("reset()\nret_val = 1\n", session.helper_env(), program="the helper")
    # without a reporter check bound, a plan's parse_completion is refused, naming what it is
    with pytest.raises(PlanError, match="text reporter's check"):
        session.prepare("judge = parse_completion('x')\n", session.plan_env(), program="the plan")


# ------------------------------------------------------------------------------------------------
# parse_completion() in a plan, end to end
# ------------------------------------------------------------------------------------------------
SELF_CHECKING_PLAN = f"""
blocks = [n for n in objects if ' block ' in n]
put_first_on_second(blocks[0], {PURPLE!r})
if not parse_completion('all blocks stacked in the orange zone', f'object_positions = {{get_obj_pos_dict()}}'):
    say('trying again')
    reset()
    stack_objects_in_order(object_names=blocks, targ={ORANGE!r})
say(f"checked again: {{parse_completion('all blocks stacked in the orange zone')}}")
"""
CHECKER = f"""
zx, zy, _ = object_positions[{ORANGE!r}][0]
inside = [n for n in blocks if abs(object_positions[n][0][0] - zx) < 0.06 and abs(object_positions[n][0][1] - zy) < 0.06]
judge = len(inside) == len(blocks)
reason = f'{{len(inside)}} of {{len(blocks)}} blocks in the orange zone'
"""


def test_a_plan_checks_itself_resets_and_retries_within_one_attempt(server) -> None:  # noqa: ANN001
    router = Router(planner=code(SELF_CHECKING_PLAN), parse_completion=code(CHECKER))
    server.respond_with(router)
    rec = MemoryRecorder()
    result = run_episode(get_task(TASK), SEED, agent(server, reporter="none", attempts=1), recorder=rec)

    assert result.success, (result.error, result.diagnostics)
    assert result.attempts == 1 and result.primitives == 1 + 5  # the put before the reset still counts
    (attempt,) = result.llm.attempts
    assert attempt.said == ("trying again", "checked again: True")
    assert router.seen == ["planner", "parse_completion", "parse_completion"]
    checks = rec.texts["llm/attempt1/plan_check/1"] + rec.texts["llm/attempt1/plan_check/2"]
    assert "-> False" in checks[0] and "0 of 5 blocks" in checks[0]  # judged on the scene after one put
    assert "-> True" in checks[1] and "5 of 5 blocks" in checks[1]
    assert len(rec.texts["planner/reset"]) == 1
