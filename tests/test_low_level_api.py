"""The low-level planner API (``--api low``) and ``--examples full|none`` (issue #48).

The low level is a second surface over the same facade as the high level: its calls land in the
same call log, its moves count against the episode's budget and go to the recorder, and a move
the arm cannot or must not make is an error class, never a crash.  Its reference plans solve the
tasks with nothing but these functions; its prompt's examples run against real scenes.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from capmj.agents.api.low_level import LOW_LEVEL_FUNCTIONS
from capmj.agents.api.low_level_robot import MOVES_PER_PRIMITIVE
from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.base import Budget, EpisodeContext
from capmj.agents.factory import make_agent
from capmj.agents.llm_agent.levels import LOW_LEVEL_ACTIONS, LevelSession
from capmj.agents.prompt_files import PLANNER_PROMPTS, load_prompt, planner_prompt
from capmj.agents.reference import reference_plan
from capmj.agents.sandbox import run_code
from capmj.bench.failures import classify
from capmj.errors import BudgetExceeded, CollisionDetected, ConfigError, PlanError, UnreachablePose
from capmj.runner import run_episode, start_episode
from capmj.sim.objects import ObjectSpec
from capmj.sim.world import World
from capmj.tasks.protocol import Scene
from capmj.tasks.registry import get_task, resolve
from prompt_examples import ExampleLLM, build_context


class _Recorder:
    """Keeps the primitives an episode sends (the rest of the Recorder protocol does nothing)."""

    def __init__(self) -> None:
        self.primitives: list[dict] = []

    def primitive(self, index, time, info) -> None:  # noqa: ANN001
        self.primitives.append(dict(info))

    def __getattr__(self, name):  # noqa: ANN001, ANN204 - attach, frame, text, image, depth, close
        return lambda *a, **k: None


class _Task:
    name = "low-level-test"
    tags = frozenset()

    def evaluate(self, scene, state):  # noqa: ANN001, ANN201
        raise AssertionError("not judged")


def _context(objects: list[ObjectSpec], budget: Budget | None = None, recorder=None) -> EpisodeContext:  # noqa: ANN001
    world = World(tuple(objects))
    world.settle()
    return EpisodeContext(_Task(), 0, Scene(tuple(objects), "test", {}), world, budget=budget, recorder=recorder)


def _block(i: int, x: float, y: float, color: str = "red") -> ObjectSpec:
    return ObjectSpec(i, "block", color, (x, y, 0.02), 0.0, "small")


@pytest.fixture
def low() -> tuple[EpisodeContext, PlannerAPI, dict]:
    ctx = _context([_block(1, 0.5, 0.0), _block(2, 0.45, 0.2, "blue")], recorder=_Recorder())
    api = PlannerAPI(ctx)
    return ctx, api, api.functions("low")


def test_the_low_level_offers_a_robot_driver_and_no_pick_and_place(low) -> None:
    _, api, fns = low
    assert tuple(fns) == LOW_LEVEL_FUNCTIONS
    assert not {"put_first_on_second", "stack_objects_in_order", "get_obj_pos"} & set(fns)
    assert set(api.functions()) >= {"put_first_on_second"}  # the high level is unchanged
    with pytest.raises(ConfigError, match="valid levels: high, low"):
        api.functions("middle")


def test_a_pick_and_place_from_low_level_calls_is_logged_counted_and_recorded(low) -> None:
    ctx, api, f = low
    block = f["get_object"]("movable small red block with obj_id 1")
    x, y, _ = block["position"]
    f["move_to_pose"]([x, y, block["bbox"][5] + 0.03], 0.0)
    assert f["move_until_contact"]([x, y, block["bbox"][5] - 0.02]) is True
    assert f["suction_on"]() is True and f["is_holding"]() is True
    f["move_to_pose"]([0.4, -0.2, 0.12])
    assert f["move_until_contact"]([0.4, -0.2, -0.03]) is True
    f["suction_off"]()
    assert f["is_holding"]() is False
    pos = ctx.world.pose(1).pos
    assert math.hypot(pos[0] - 0.4, pos[1] + 0.2) < 0.01 and abs(pos[2] - 0.02) < 0.003
    assert [e["fn"] for e in api.call_log] == ["get_object", "move_to_pose", "move_until_contact", "suction_on",
                                               "is_holding", "move_to_pose", "move_until_contact", "suction_off",
                                               "is_holding"]
    assert ctx.attempt_primitives == 4  # the four moves, not the suction switches
    moves = ctx.recorder.primitives
    assert [m["fn"] for m in moves] == ["move_to_pose", "move_until_contact", "move_to_pose", "move_until_contact"]
    assert moves[1]["contact"] is True and moves[3]["obj_id"] == 1 and all(m["ok"] for m in moves)
    assert [m["status"] for m in moves] == ["ok", "contact", "ok", "contact"]
    assert all(m["planned"] == () for m in moves)  # nothing in the way: no path planned around anything


def test_a_move_into_the_table_or_out_of_reach_is_refused_before_the_arm_moves(low) -> None:
    ctx, _, f = low
    q0 = ctx.world.arm_q()
    with pytest.raises(UnreachablePose, match="below the table top") as exc:
        f["move_linear"]([0.5, 0.0, -0.02])
    assert exc.value.status == "below_table"
    with pytest.raises(UnreachablePose, match="out of reach") as exc:
        f["move_to_pose"]([1.5, 0.0, 0.2])
    assert exc.value.status == "unreachable"
    with pytest.raises(UnreachablePose, match="no IK solution"):
        f["solve_ik"]([0.0, 1.4, 0.1])
    with pytest.raises(UnreachablePose, match="beyond their limits"):
        f["move_to_joints"]([0.0, 0.0, 9.0, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"\[x, y, z\]"):
        f["move_linear"]([0.5, 0.0])
    assert np.allclose(ctx.world.arm_q(), q0, atol=1e-3) and ctx.attempt_primitives == 0
    q = f["solve_ik"]([0.5, 0.1, 0.15], 0.3)
    f["move_to_joints"](q)
    tip, yaw = f["get_ee_pose"]()
    assert np.allclose(tip, [0.5, 0.1, 0.15], atol=0.003) and abs(yaw - 0.3) < 0.01
    f["home"]()


def test_a_straight_move_through_an_object_stops_as_a_collision(low) -> None:
    ctx, _, f = low
    f["move_to_pose"]([0.5, -0.1, 0.02], 0.0)  # beside the red block, low
    with pytest.raises(CollisionDetected, match="movable small red block with obj_id 1") as exc:
        f["move_linear"]([0.5, 0.1, 0.02])
    assert exc.value.status == "collision"
    tip = ctx.world.tip_pose()[0]
    assert tip[1] < 0.0  # stopped at the block, not pushed through it
    assert ctx.recorder.primitives[-1]["status"] == "collision"


def test_the_move_budget_is_max_primitives_times_moves_per_primitive() -> None:
    ctx = _context([_block(1, 0.5, 0.0)], budget=Budget(max_primitives=1))
    f = PlannerAPI(ctx).functions("low")
    for k in range(MOVES_PER_PRIMITIVE):
        f["move_linear"]([0.45, 0.0, 0.2 + 0.01 * (k % 2)])
    with pytest.raises(BudgetExceeded, match=f"{MOVES_PER_PRIMITIVE} low-level moves"):
        f["home"]()


def test_rgbd_objects_are_the_perceived_detections_not_the_truth() -> None:
    from capmj.agents.api.perceived import make_api

    ctx = start_episode(get_task("stack-all-blocks-on-a-zone"), 10001)
    api = make_api(ctx, "rgbd")
    f = api.functions("low")
    seen = f["get_objects"]()
    scene = api.scene  # type: ignore[attr-defined]
    truth = {o.obj_id: np.asarray(ctx.world.pose(o.obj_id).pos) for o in ctx.world.objects}
    assert [o["name"] for o in seen] == [o.name for o in scene.objects]
    errors = []
    for o in seen:
        assert o["position"] == [float(v) for v in scene.pose(o["obj_id"]).pos]
        errors.append(float(np.linalg.norm(np.asarray(o["position"]) - truth[o["obj_id"]])))
    assert max(errors) > 1e-4  # estimated, not read from the simulator
    images = f["get_camera_images"]()
    front = images["front"]
    assert front["rgb"].dtype == np.uint8 and front["depth"].shape == front["rgb"].shape[:2]
    assert front["intrinsics"].shape == (3, 3) and front["extrinsics"].shape == (4, 4)


LOW_TASKS = ["stack-blocks-with-alternate-color", "put-block-into-mismatching-bowl", "zone-bisector"]


@pytest.mark.parametrize("name", LOW_TASKS)
def test_low_level_reference_plans_run_with_examples_none(name: str) -> None:
    agent = make_agent("reference", api="low", examples="none")
    r = run_episode(get_task(name), 10001, agent)
    assert r.error is None, r.error
    assert r.success, (r.goal, r.diagnostics)
    assert r.primitives >= 4  # moves, counted one by one


def test_every_task_has_a_low_level_plan_written_against_the_low_level_only() -> None:
    high_only = {"put_first_on_second", "stack_objects_in_order", "get_obj_pos", "get_bbox", "get_color",
                 "get_random_free_pos", "is_target_occupied"}
    for name in resolve("all"):
        code, source = reference_plan(get_task(name), "low")
        assert source.endswith(f"low/{name}.py")
        assert "import" not in code and "info" not in code
        assert not any(f"{fn}(" in code for fn in high_only), name


def test_a_collision_in_an_episode_is_labelled_collision() -> None:
    class _Crash:
        """Drives the cup straight down into a block instead of a guarded descent."""

        name, model = "reference", None

        def act(self, ctx: EpisodeContext) -> None:
            code = ("b = [o for o in get_objects() if o['kind'] == 'block'][0]\n"
                    "x, y, z = b['position']\n"
                    "move_to_pose([x, y, z + 0.06])\n"
                    "move_linear([x, y, z])\n")
            run_code(code, dict(PlannerAPI(ctx).functions("low")))

    r = run_episode(get_task("stack-all-blocks-on-a-zone"), 10001, _Crash())
    assert r.error_type == "CollisionDetected", r.error
    assert classify(r) == "collision"


@pytest.mark.parametrize("api", sorted(PLANNER_PROMPTS))
def test_examples_none_leaves_the_api_section_identical_and_no_example(api: str) -> None:
    full, none = planner_prompt(api, "full"), planner_prompt(api, "none")
    assert full.examples and not none.examples
    head = full.template.split(full.examples[0].body.splitlines()[0])[0]
    assert none.template.startswith(head.rstrip("\n"))
    assert none.template.rstrip("\n").endswith("<<QUESTION>>")
    for ex in full.examples:
        assert ex.body not in none.template
    assert "objects = [" not in none.template
    with pytest.raises(ConfigError, match="valid: full, none"):
        planner_prompt(api, "some")


def test_the_low_level_session_sends_the_level_prompt_and_keeps_moves_from_helpers(low) -> None:
    _, api, f = low
    session = LevelSession(complete=ExampleLLM(), api=f, objects_text=api.objects_text, api_level="low",
                           examples="none")
    assert session.prompt("planner").template == planner_prompt("low", "none").template
    assert "move_to_pose" in session.plan_env()
    assert not LOW_LEVEL_ACTIONS & set(session.helper_env())
    assert session.prompt("parse_obj_name").name == "parse_obj_name"


@pytest.mark.parametrize("example", load_prompt("planner_low").examples, ids=lambda e: e.id)
def test_planner_low_example_succeeds(example) -> None:  # noqa: ANN001
    ctx = build_context(example)
    api = PlannerAPI(ctx)
    f = api.functions("low")
    env = dict(f)
    env["objects"] = api.object_names()
    run_code(example.body, env, filename=f"<planner_low/{example.id}>")
    assert ctx.attempt_primitives >= 1
    if "task" in example.meta:
        verdict = ctx.verdict()
        assert verdict.success, (example.id, verdict.diagnostics)
    else:
        ctx.world.settle(max_steps=1000)
    checks = [e for e in example.meta.get("check", "").splitlines() if e.strip()]
    assert "task" in example.meta or checks
    for expr in checks:
        ns = run_code(f"check_result = bool({expr})", dict(f), filename="<check>")
        assert ns["check_result"] is True, (example.id, expr)


def test_a_plan_error_at_the_low_level_names_its_class() -> None:
    ctx = _context([_block(1, 0.5, 0.0)])
    f = PlannerAPI(ctx).functions("low")
    with pytest.raises(PlanError, match="UnreachablePose"):
        run_code("move_linear([0.5, 0.0, -0.1])", dict(f))


def test_llm_options_check_the_level() -> None:
    from capmj.agents.llm_agent.options import LLMAgentOptions

    assert (LLMAgentOptions(api="low", examples="none").api, LLMAgentOptions().examples) == ("low", "full")
    with pytest.raises(ConfigError, match="valid levels: high, low"):
        LLMAgentOptions(api="lowest")
    with pytest.raises(ConfigError, match="--api low runs with --policy code"):
        LLMAgentOptions(api="low", policy="tools")


def test_the_llm_agent_plans_at_the_low_level_without_examples() -> None:
    """--agent llm --api low --examples none against the scripted server: the prompt sent is the
    low level's without examples, and the answered low-level plan runs to success."""
    from capmj.agents.llm_agent.agent import LLMAgent
    from capmj.agents.llm_agent.options import LLMAgentOptions
    from capmj.llm import LLMConfig
    from llm_stub_server import StubLLMServer, prompt_text

    code, _ = reference_plan(get_task("stack-all-blocks-on-a-zone"), "low")
    with StubLLMServer(default_text=f"```python\n{code}```") as server:
        agent = LLMAgent(LLMConfig("openai/stub", api_base=server.base_url, backoff_s=0.0, timeout_s=10.0),
                         LLMAgentOptions(api="low", examples="none"))
        r = run_episode(get_task("stack-all-blocks-on-a-zone"), 10001, agent)
        sent = prompt_text(server.requests[0])
    assert r.success, (r.error, r.diagnostics)
    head = planner_prompt("low", "none").template.split("<<QUESTION>>")[0]
    assert head.strip() in sent and "#@" not in sent
    assert "put_first_on_second" not in sent and sent.count("objects = [") == 1  # the question's, no example's


def test_the_command_line_and_the_manifest_carry_api_and_examples() -> None:
    from capmj.bench.cli import build_parser
    from capmj.bench.manifest import build_manifest
    from capmj.bench.options import given_agent_options

    args = build_parser().parse_args(["--agent", "reference", "--api", "low", "--examples", "none"])
    options = given_agent_options(args)
    assert options == {"api": "low", "examples": "none"}
    agent = make_agent("reference", **options)
    task = [get_task("stack-all-blocks-on-a-zone")]
    assert build_manifest(agent, task)["api"] == {"level": "low", "examples": "none"}
    assert "api" not in build_manifest(make_agent("reference"), task)  # the defaults leave manifests as they were
    with pytest.raises(SystemExit):
        build_parser().parse_args(["--agent", "reference", "--api", "middle"])
