"""The reference agent: runs the hand-written plan of a task through the planner API and sandbox.

A reference plan is the code a perfect planner would write for the task: it sees exactly what LLM
code sees — the API functions of :class:`~capmj.agents.api.planner_api.PlannerAPI`, the goal text as ``goal``
and the object names as ``objects`` — and runs in the same sandbox.  It never reads the task's
``scene.info``; everything (colours, sizes, areas, directions) is parsed from the goal text and
measured through the API.  Its success rate is therefore a check of the API, the sandbox, the
tasks and the physics together: a failing reference episode is a bug in one of them.

Plans are looked up, in order: a ``reference_plan`` string attribute of the task object (plugins
can ship their own), ``$CAPMJ_PROMPTS_DIR/reference/<task-name>.py``, then
``reference/<task-name>.py`` in the packaged ``prompts/`` folder.  At the low API level
(``api="low"``, :mod:`capmj.agents.api.low_level`) the plans are ``reference/low/<task-name>.py``
(a task's ``reference_plan_low`` attribute first), written against that API alone.
"""

from __future__ import annotations

import os
from pathlib import Path

from capmj.agents.api.low_level import LEVELS
from capmj.agents.api.perceived import make_api
from capmj.agents.base import EpisodeContext
from capmj.agents.prompt_files import EXAMPLES
from capmj.agents.sandbox import SandboxBudget, run_code
from capmj.errors import AgentError, ConfigError
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


HELPERS = "_helpers.py"
"""A file of a plan folder run before each plan file of that folder (the low level's pick and place
are written once, from guarded moves and the suction, for all its plans)."""


def reference_plan(task, api: str = "high") -> tuple[str, str]:
    """``(code, source)`` of the reference plan of a task at an API level (``high`` or ``low``):
    the task's own ``reference_plan[_low]`` attribute, else ``reference[/low]/<task>.py`` of the
    prompt folders, preceded by the folder's :data:`HELPERS` when it has one; raises AgentError when
    there is none."""
    if api not in LEVELS:
        raise ConfigError(f"unknown API level {api!r}; valid levels: {', '.join(LEVELS)}")
    attr = "reference_plan" if api == "high" else f"reference_plan_{api}"
    own = getattr(task, attr, None)
    if isinstance(own, str) and own.strip():
        return own, f"<{task.name}.{attr}>"
    name = getattr(task, "name", str(task))
    folder = Path("reference") if api == "high" else Path("reference") / api
    tried = []
    for d in prompts_dirs():
        path = d / folder / f"{name}.py"
        tried.append(str(path))
        if path.is_file():
            helpers = path.parent / HELPERS
            shared = helpers.read_text(encoding="utf-8") + "\n\n" if helpers.is_file() else ""
            return shared + path.read_text(encoding="utf-8"), str(path)
    raise AgentError(f"no reference plan for task {name!r}; looked for {', '.join(tried)} "
                     f"and a {attr!r} attribute on the task")


class ReferenceAgent:
    """Runs the task's hand-written plan in the sandbox with the planner API."""

    name = "reference"
    model = None

    def __init__(self, budget: SandboxBudget | None = None, perception: str = "state", api: str = "high",
                 examples: str = "full") -> None:
        if api not in LEVELS:
            raise ConfigError(f"unknown API level {api!r}; valid levels: {', '.join(LEVELS)}")
        if examples not in EXAMPLES:
            raise ConfigError(f"unknown examples choice {examples!r}; valid: {', '.join(EXAMPLES)}")
        self.budget = budget or REFERENCE_BUDGET
        self.perception = perception
        """``state`` (the API reads the simulator) or ``rgbd`` (the cameras: :mod:`capmj.agents.api.perceived`)."""
        self.api = api
        """The planner API level its plans are written against: ``high`` or ``low`` (:data:`~capmj.agents.api.low_level.LEVELS`)."""
        self.examples = examples
        """Accepted and recorded like the LLM agent's ``--examples``, so one grid can sweep it: the
        reference agent reads no prompt, so its plans run the same either way."""

    def act(self, ctx: EpisodeContext) -> None:
        code, source = reference_plan(ctx.task, self.api)
        api = make_api(ctx, self.perception)
        env: dict[str, object] = dict(api.functions(self.api))
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
