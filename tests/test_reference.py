"""The reference plans solve every registered task through the planner API, sandbox and physics."""

from __future__ import annotations

import pytest

from capmj.agents.reference import ReferenceAgent, reference_plan
from capmj.errors import AgentError
from capmj.runner import run_episode
from capmj.tasks.builtin import BENCHMARK_TASKS
from capmj.tasks.registry import get_task, resolve

BENCHMARK = list(BENCHMARK_TASKS)
ALL = resolve("all")
"""Every registered task: each must have a reference plan."""


def test_every_task_has_a_plan():
    assert sorted(resolve("benchmark")) == sorted(BENCHMARK)
    for name in ALL:
        code, source = reference_plan(get_task(name))
        assert code.strip() and source.endswith(f"{name}.py")
        assert "info" not in code and "import" not in code  # derived from the goal and the API only


@pytest.mark.parametrize("seed", [10001, 10003])
@pytest.mark.parametrize("name", ALL)
def test_reference_solves(name, seed):
    r = run_episode(get_task(name), seed, ReferenceAgent())
    assert r.error is None, r.error
    assert r.success, (r.goal, r.diagnostics)
    assert r.primitives >= 1 and r.agent == "reference" and r.model is None


class _Plugin:
    """A task object that carries its own reference plan (as a plugin may)."""

    def __init__(self, base, plan):
        self._base, self.reference_plan, self.name, self.tags = base, plan, base.name, base.tags

    def sample_scene(self, rng):
        return self._base.sample_scene(rng)

    def oracle_goals(self, scene):
        return self._base.oracle_goals(scene)

    def evaluate(self, scene, state):
        return self._base.evaluate(scene, state)


def test_task_supplied_plan_and_plan_errors_are_recorded():
    base = get_task("stack-all-blocks-on-a-zone")
    r = run_episode(_Plugin(base, "say(goal)\n"), 10001, ReferenceAgent())
    assert r.error is None and not r.success and r.primitives == 0
    r = run_episode(_Plugin(base, "x = 1\nput_first_on_second(objects[0], objects[0])\n"), 10001, ReferenceAgent())
    assert r.error is not None and r.error.startswith("PlanError: line 2: ValueError")


def test_missing_plan_is_an_agent_error():
    class NoPlan:
        name = "no-such-task"

    with pytest.raises(AgentError, match="no reference plan for task 'no-such-task'"):
        reference_plan(NoPlan())
