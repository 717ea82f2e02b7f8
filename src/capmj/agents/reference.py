"""The reference agent: runs the hand-written plan of a task through the planner API and sandbox.

A reference plan is the code a perfect planner would write for the task: it sees exactly what LLM
code sees — the API functions of :class:`~capmj.agents.api.planner_api.PlannerAPI`, the goal text as ``goal``
and the object names as ``objects`` — and runs in the same sandbox.  It never reads the task's
``scene.info``; everything (colours, sizes, areas, directions) is parsed from the goal text and
measured through the API.  Its success rate is therefore a check of the API, the sandbox, the
tasks and the physics together: a failing reference episode is a bug in one of them.

Plans are looked up, in order: a ``reference_plan`` string attribute of the task object (plugins
can ship their own), ``$CAPMJ_PROMPTS_DIR/reference/<task-name>.py``, then
``reference/<task-name>.py`` in the packaged ``prompts/`` folder.
"""

from __future__ import annotations

import os
from pathlib import Path

from capmj.agents.api.perceived import make_api
from capmj.agents.base import EpisodeContext
from capmj.agents.sandbox import SandboxBudget, run_code
from capmj.errors import AgentError
from capmj.resources import PROMPTS_ENV, packaged


REFERENCE_BUDGET = SandboxBudget(wall_s=600.0, max_api_calls=2000)
"""Physics time is budgeted in simulation steps by the episode context; the wall-time limit here
only catches a plan that hangs, so it is far above any real episode."""


def prompts_dirs() -> list[Path]:
    """Where prompt files are looked up, first match wins."""
    dirs = []
    env = os.environ.get(PROMPTS_ENV, "").strip()
    if env:
        dirs.append(Path(env))
    dirs.append(packaged("prompts"))
    return dirs


def reference_plan(task) -> tuple[str, str]:
    """``(code, source)`` of the reference plan of a task; raises AgentError when there is none."""
    own = getattr(task, "reference_plan", None)
    if isinstance(own, str) and own.strip():
        return own, f"<{task.name}.reference_plan>"
    name = getattr(task, "name", str(task))
    tried = []
    for d in prompts_dirs():
        path = d / "reference" / f"{name}.py"
        tried.append(str(path))
        if path.is_file():
            return path.read_text(encoding="utf-8"), str(path)
    raise AgentError(f"no reference plan for task {name!r}; looked for {', '.join(tried)} "
                     "and a 'reference_plan' attribute on the task")


class ReferenceAgent:
    """Runs the task's hand-written plan in the sandbox with the planner API."""

    name = "reference"
    model = None

    def __init__(self, budget: SandboxBudget | None = None, perception: str = "state") -> None:
        self.budget = budget or REFERENCE_BUDGET
        self.perception = perception
        """``state`` (the API reads the simulator) or ``rgbd`` (the cameras: :mod:`capmj.agents.api.perceived`)."""

    def act(self, ctx: EpisodeContext) -> None:
        code, source = reference_plan(ctx.task)
        api = make_api(ctx, self.perception)
        env: dict[str, object] = dict(api.functions())
        env["goal"] = ctx.scene.goal
        env["objects"] = api.object_names()
        ctx.recorder.text("reference/plan", f"# {source}\n{api.objects_text()}\n# {ctx.scene.goal}\n{code}")
        output: list[str] = []
        try:
            run_code(code, env, budget=self.budget, filename=f"<reference:{ctx.task.name}>", output=output)
        finally:
            ctx.notes["api_calls"] = list(api.call_log)
            ctx.notes["say"] = list(api.messages)
            ctx.recorder.text("reference/api_calls", api.log_text())
            if output:
                ctx.recorder.text("reference/print", "\n".join(output))


__all__ = ["PROMPTS_ENV", "REFERENCE_BUDGET", "ReferenceAgent", "prompts_dirs", "reference_plan"]
