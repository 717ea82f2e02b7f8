"""The oracle solves every registered task through real physics, and the episode runner
turns every kind of failure into a recorded result instead of an exception."""

from __future__ import annotations

import numpy as np
import pytest

from capmj.agents.oracle import OracleAgent
from capmj.runner import run_episode
from capmj.tasks.protocol import Scene
from capmj.tasks.registry import get_task, resolve

ALL = resolve("all")
"""Every registered task (A–J, the generated tasks, anything else installed as a plugin)."""


def test_registry_has_the_ten_benchmark_tasks() -> None:
    assert len(resolve("benchmark")) == 10
    assert "stack-all-blocks-on-a-zone" in ALL


@pytest.mark.parametrize("name", ALL)
@pytest.mark.parametrize("seed", [10001, 10003])
def test_oracle_solves_task(name: str, seed: int) -> None:
    res = run_episode(get_task(name), seed, OracleAgent())
    assert res.error is None, res.error
    assert res.success, res.diagnostics
    assert res.progress == 1.0 and res.reward == pytest.approx(1.0)
    assert res.primitives >= 1 and res.sim_s > 0


class _Raising:
    name = "raising"
    model = None

    def act(self, ctx) -> None:  # noqa: ANN001
        ctx.pick_and_place(np.array(ctx.world.pose(ctx.world.movable_ids[0]).pos), np.array([0.5, 0.3]))
        raise RuntimeError("agent bug")


class _BrokenTask:
    name = "broken-task"
    tags = frozenset()

    def sample_scene(self, rng):  # noqa: ANN001
        raise ZeroDivisionError("generator bug")

    def oracle_goals(self, scene: Scene):  # noqa: ANN201
        return []

    def evaluate(self, scene, state):  # noqa: ANN001, ANN201
        raise AssertionError("unreachable")


def test_runner_records_agent_exceptions_as_failed_episodes() -> None:
    res = run_episode(get_task("stack-all-blocks-on-a-zone"), 10001, _Raising())
    assert not res.success
    assert res.error == "RuntimeError: agent bug"
    assert res.primitives == 1
    assert res.diagnostics  # the verdict still explains the final state


def test_runner_records_broken_tasks_as_failed_episodes() -> None:
    res = run_episode(_BrokenTask(), 1, OracleAgent())
    assert not res.success and res.error == "ZeroDivisionError: generator bug"


def test_reset_restores_the_initial_state_and_motion_stays_fast() -> None:
    from capmj.agents.base import EpisodeContext
    from capmj.sim.world import World
    from capmj.tasks.protocol import make_scene

    task = get_task("stack-all-blocks-on-a-zone")
    scene = make_scene(task, 10001)
    world = World(scene.objects)
    ctx = EpisodeContext(task, 10001, scene, world)
    block = world.movable_ids[0]
    start = np.asarray(world.pose(block).pos)
    first = ctx.pick_and_place(start, np.array([0.45, 0.3]), 2.5)  # ends with the wrist turned
    assert first.ok
    ctx.reset()
    assert np.allclose(world.pose(block).pos, start, atol=1e-9)
    assert ctx.attempt_primitives == 0 and ctx.attempt == 1
    again = ctx.pick_and_place(start, np.array([0.45, 0.3]), 2.5)
    assert again.ok and again.steps == first.steps  # same motion from the same state
