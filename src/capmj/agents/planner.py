"""The planner LMP (CapRavens' ``tabletop_ui``): goal -> whole plan as code -> sandboxed run.

The prompt is ``prompts/planner.py`` with ``objects = [...]`` (from the live API) and the goal as
a comment appended.  On a re-plan the previous plan and the failure report follow as a second
turn, so the model writes a *new* complete plan for the reset scene (CapRavens re-ran the old plan
first).  The completion's code gets benign import echoes removed, functions it calls but nobody
defined written by ``parse_function``, and then runs in the sandbox with the whole planner API,
``parse_obj_name`` / ``parse_position``, ``objects`` and ``goal``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from capmj.agents.lmp import LMPCall, LMPSession, object_names
from capmj.agents.sandbox import SandboxBudget, extract_code, run_code
from capmj.errors import PlanError

__all__ = ["DEFAULT_PLAN_BUDGET", "Feedback", "PlanOutcome", "build_messages", "plan_and_run"]

DEFAULT_PLAN_BUDGET = SandboxBudget(wall_s=60.0, max_api_calls=2000, max_lines=100_000)
"""Deterministic: 100 000 executed lines (loop iterations included), 2000 API calls, the
sandbox's element caps; physics is budgeted in simulation steps and primitives by the episode
context.  The wall time is a backstop for the plan's own Python only: time inside API functions
(simulation, helper LMP calls waiting on the LLM) is not counted."""


@dataclass(frozen=True)
class Feedback:
    """What the next attempt learns about the previous one."""

    completion: str
    report: str


@dataclass
class PlanOutcome:
    """What happened in one planning attempt (filled as far as it got)."""

    call: LMPCall | None = None
    completion: str | None = None
    code: str | None = None
    output: list[str] = field(default_factory=list)


def question(objects_text: str, goal: str) -> str:
    return f"{objects_text.strip()}\n# {' '.join(goal.split())}"


def build_messages(session: LMPSession, goal: str, feedback: Feedback | None = None) -> list[dict[str, Any]]:
    """The planner conversation for ``goal`` (with the previous attempt when re-planning)."""
    q = question(session.objects_text(), goal)
    messages = session.messages(session.prompt("planner").render(q))
    if feedback is not None:
        report = "\n".join(f"# {line}" if line.strip() else "#" for line in feedback.report.splitlines())
        messages += [
            {"role": "assistant", "content": feedback.completion},
            {"role": "user", "content": (
                "# The plan above was executed and did not achieve the goal:\n"
                f"{report}\n"
                "# The scene has been reset to its initial state. Write a new complete plan for the same goal.\n"
                f"{q}\n")},
        ]
    return messages


def plan_and_run(session: LMPSession, goal: str, *, feedback: Feedback | None = None,
                 budget: SandboxBudget = DEFAULT_PLAN_BUDGET,
                 outcome: PlanOutcome | None = None) -> PlanOutcome:
    """Ask for a plan and run it.  Raises LLMError (provider) or PlanError (code); ``outcome``
    (when given) holds the completion and executed code even then."""
    out = outcome if outcome is not None else PlanOutcome()
    call = session.next_call("planner", goal)
    out.call = call
    out.completion = session.ask(call, build_messages(session, goal, feedback))
    env = session.plan_env()
    env["objects"] = object_names(session.objects_text()) or []
    env["goal"] = goal
    try:
        code = extract_code(out.completion)
        code = session.prepare(code, env, parent=call, program="the plan")
        out.code = code
        session.record(call, "code", code)
        run_code(code, env, budget=budget, filename=f"<plan attempt {session.attempt}>", output=out.output,
                 program="the plan", rng=session.rng)
    except PlanError as exc:
        session.record(call, "error", f"{type(exc).__name__}: {exc}")
        raise
    finally:
        if out.output:
            session.recorder.text(f"llm/attempt{session.attempt}/planner/{call.n}/printed", "\n".join(out.output))
    session.record(call, "result", "plan finished")
    return out
