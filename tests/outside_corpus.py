"""Running the outside-plan corpus (``tests/outside_plans/<task>.py``) like LLM code.

A plan runs through :class:`~capmj.agents.reference.ReferenceAgent` on a task wrapper that
carries the plan as its ``reference_plan``: the same sandbox, planner API, ``objects`` and
``goal`` that LLM plan code gets, and the task's own predicate judges the settled scene.
Shared by ``tests/test_outside_plans.py`` and ``python tests/outside_corpus.py`` (a table of
passes per task over more seeds).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from capmj.agents.reference import ReferenceAgent
from capmj.runner import run_episode
from capmj.tasks.registry import get_task

PLANS = Path(__file__).parent / "outside_plans"


def plan_of(task_name: str) -> str:
    """The outside plan of a task."""
    return (PLANS / f"{task_name}.py").read_text(encoding="utf-8")


@dataclass(frozen=True)
class WithPlan:
    """A task that carries another plan as its reference plan (the predicate is the task's own)."""

    base: Any
    reference_plan: str

    @property
    def name(self) -> str:
        return self.base.name

    @property
    def tags(self) -> Any:
        return self.base.tags

    def sample_scene(self, rng):
        return self.base.sample_scene(rng)

    def oracle_goals(self, scene):
        return self.base.oracle_goals(scene)

    def evaluate(self, scene, state):
        return self.base.evaluate(scene, state)


def run_outside(task_name: str, seed: int, plan: str | None = None):
    """One episode of a task with its outside plan (or ``plan``)."""
    task = WithPlan(get_task(task_name), plan if plan is not None else plan_of(task_name))
    return run_episode(task, seed, ReferenceAgent())


if __name__ == "__main__":  # python tests/outside_corpus.py [task ...] [--seeds 10001:10011:2]
    import json

    args = sys.argv[1:]
    seeds = list(range(10001, 10011, 2))
    if "--seeds" in args:
        i = args.index("--seeds")
        a, b, *c = (int(v) for v in args[i + 1].split(":"))
        seeds = list(range(a, b, c[0] if c else 1))
        del args[i:i + 2]
    names = args or sorted(p.stem for p in PLANS.glob("*.py"))
    for name in names:
        fails = []
        for seed in seeds:
            r = run_outside(name, seed)
            if not r.success:
                fails.append({"seed": seed, "error": r.error, "diag": str(r.diagnostics)[:300]})
        print(json.dumps({"task": name, "passed": len(seeds) - len(fails), "n": len(seeds), "fails": fails}), flush=True)
