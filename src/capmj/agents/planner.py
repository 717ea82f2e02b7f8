"""The planner LMP (CapRavens' ``tabletop_ui``): goal -> whole plan as code -> sandboxed run.

The prompt is ``prompts/planner.py`` with ``objects = [...]`` (from the live API) and the goal as
a comment appended.  The completion's code gets benign import echoes removed, functions it calls
but nobody defined written by ``parse_function``, and then runs in the sandbox with the whole
planner API, ``parse_obj_name`` / ``parse_position``, ``objects`` and ``goal``.

Re-planning (CapRavens re-ran the old plan first; capmj resets the scene and runs only the new
plan): the previous completion follows as an assistant turn, then a user turn shows the plan as it
ran *with line numbers*, what happened (the error and its failing line, or the reporter's verdict,
reasons and the objects whose state is wrong), the object positions after it, and asks for a
corrected complete plan.  A small model at temperature 0 answered such requests with the very
same plan, so a re-plan that is identical (same syntax tree) to the plan of an earlier attempt is
answered once more with a request for a *different* plan; :class:`PlanOutcome` records both.
"""

from __future__ import annotations

import ast
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from capmj.agents.lmp import LMPCall, LMPSession, object_names
from capmj.agents.sandbox import SandboxBudget, extract_code, run_code
from capmj.errors import PlanError

__all__ = ["DEFAULT_PLAN_BUDGET", "Feedback", "PlanOutcome", "build_messages", "feedback_text", "plan_and_run",
           "plan_key"]

DEFAULT_PLAN_BUDGET = SandboxBudget(wall_s=900.0, max_api_calls=2000)
"""Physics is budgeted in simulation steps and primitives by the episode context; the wall time
here only stops code that hangs, and it includes the helper LMP calls a plan makes (LLM latency),
so it is generous."""


@dataclass(frozen=True)
class Feedback:
    """What the next attempt learns about the previous one."""

    attempt: int
    completion: str
    code: str | None = None
    """The plan as it ran (line numbers of errors refer to it); None when no code was found."""
    error: str | None = None
    error_line: int | None = None
    report: str = ""
    """The reporter's verdict, reasons and wrong objects (empty when the plan failed)."""
    scene: str = ""
    """Object positions after the plan."""


@dataclass
class PlanOutcome:
    """What happened in one planning attempt (filled as far as it got)."""

    call: LMPCall | None = None
    completion: str | None = None
    code: str | None = None
    output: list[str] = field(default_factory=list)
    key: str | None = None
    """:func:`plan_key` of the plan that ran."""
    identical_to: int | None = None
    """The earliest earlier attempt whose plan equals the one that ran (None: it differs)."""
    first_identical_to: int | None = None
    """Same for the first answer, when it was identical and a different plan was asked for."""
    extra_request: bool = False


def question(objects_text: str, goal: str) -> str:
    return f"{objects_text.strip()}\n# {' '.join(goal.split())}"


def plan_key(completion: str) -> str:
    """What makes two plans the same: the syntax tree of the answer's code (comments, blank lines
    and formatting ignored), else its whitespace-normalised text."""
    try:
        code = extract_code(completion)
    except PlanError:
        return " ".join(completion.split())
    try:
        return ast.dump(ast.parse(code))
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return " ".join(code.split())


def _comment(text: str) -> list[str]:
    return [f"# {line}" if line.strip() else "#" for line in text.splitlines()]


def feedback_text(feedback: Feedback) -> str:
    """The comment block of a re-plan request (without the question)."""
    out = [f"# The plan above (attempt {feedback.attempt}) ran from the initial scene and did not achieve the goal."]
    if feedback.code:
        lines = feedback.code.rstrip("\n").splitlines()
        width = len(str(len(lines)))
        out.append("# The plan as it ran, with line numbers:")
        out += [f"# {i:>{width}}| {line}" for i, line in enumerate(lines, start=1)]
        if feedback.error_line is not None and 1 <= feedback.error_line <= len(lines):
            failing = lines[feedback.error_line - 1].strip()
            out.append(f"# It failed at line {feedback.error_line}: {failing}")
    if feedback.error:
        out += _comment(f"Error: {feedback.error}")
    if feedback.report:
        out += _comment(feedback.report)
    if feedback.scene:
        out += _comment(feedback.scene)
    out.append("# The scene has been reset to its initial state. Write a corrected complete plan for the same goal: "
               "fix what went wrong, do not repeat the plan above.")
    return "\n".join(out)


def build_messages(session: LMPSession, goal: str, feedback: Feedback | None = None) -> list[dict[str, Any]]:
    """The planner conversation for ``goal`` (with the previous attempt when re-planning)."""
    q = question(session.objects_text(), goal)
    messages = session.messages(session.prompt("planner").render(q))
    if feedback is not None:
        messages += [
            {"role": "assistant", "content": feedback.completion},
            {"role": "user", "content": f"{feedback_text(feedback)}\n{q}\n"},
        ]
    return messages


def plan_and_run(session: LMPSession, goal: str, *, feedback: Feedback | None = None,
                 previous: Sequence[str | None] = (), budget: SandboxBudget = DEFAULT_PLAN_BUDGET,
                 outcome: PlanOutcome | None = None) -> PlanOutcome:
    """Ask for a plan and run it.  Raises LLMError (provider) or PlanError (code); ``outcome``
    (when given) holds the completion and executed code even then.

    ``previous`` are the :func:`plan_key` of the plans of attempts 1, 2, ...; an answer equal to
    one of them is asked once more for a different plan (and the second answer is used)."""
    out = outcome if outcome is not None else PlanOutcome()
    call = session.next_call("planner", goal)
    out.call = call
    messages = build_messages(session, goal, feedback)
    out.completion = session.ask(call, messages)
    out.key = plan_key(out.completion)
    if out.key in previous:
        out.first_identical_to = list(previous).index(out.key) + 1
        out.extra_request = True
        session.recorder.text(f"llm/attempt{session.attempt}/planner/{call.n}/identical_to",
                              f"identical to the plan of attempt {out.first_identical_to}; asking for a different plan")
        messages = messages + [
            {"role": "assistant", "content": out.completion},
            {"role": "user", "content": (
                f"# This plan is identical to the plan of attempt {out.first_identical_to}, which did not achieve "
                "the goal. Write a different complete plan that fixes what went wrong.\n"
                f"{question(session.objects_text(), goal)}\n")},
        ]
        call = out.call = session.next_call("planner", goal)
        out.completion = session.ask(call, messages)
        out.key = plan_key(out.completion)
    out.identical_to = list(previous).index(out.key) + 1 if out.key in previous else None
    env = session.plan_env()
    env["objects"] = object_names(session.objects_text()) or []
    env["goal"] = goal
    try:
        code = out.code = extract_code(out.completion)
        code = out.code = session.prepare(code, env, parent=call)
        session.record(call, "code", code)
        run_code(code, env, budget=budget, filename=f"<plan attempt {session.attempt}>", output=out.output)
    except PlanError as exc:
        session.record(call, "error", f"{type(exc).__name__}: {exc}")
        raise
    finally:
        if out.output:
            session.recorder.text(f"llm/attempt{session.attempt}/planner/{call.n}/printed", "\n".join(out.output))
    session.record(call, "result", "plan finished")
    return out
