"""The planner LMP (CapRavens' ``tabletop_ui``): goal -> whole plan as code -> sandboxed run.

The prompt is ``prompts/planner.py`` with ``objects = [...]`` (from the live API) and the goal as
a comment appended.  The completion's code gets benign import echoes removed, functions it calls
but nobody defined written by ``parse_function``, and then runs in the sandbox with the whole
planner API, ``parse_obj_name`` / ``parse_position``, ``objects`` and ``goal``.

Re-planning (CapRavens re-ran the old plan first; capmj resets the scene and runs only the new
plan): the previous completion follows as an assistant turn, then a user turn shows the plan as it
ran *with line numbers*, what happened (the error and its failing line, or the reporter's verdict,
reasons and the objects whose state is wrong), the object positions after it, and asks for a
corrected complete plan.  A small model answered such requests with the very same plan (at
temperature 0 always, at 0.7 still 5 of 7 times), so an answer identical (same syntax tree) to the
plan of an earlier attempt is asked again, up to ``retries`` times, each time at the temperature and
seed of :func:`replan_sampling` and with the failure of that attempt repeated.  A plan still
identical after the retries is not run: the scene was reset to the same initial state and physics is
deterministic, so it would end as that attempt did.  :class:`PlanOutcome` records all of it.
"""

from __future__ import annotations

import ast
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from capmj.agents.lmp.session import Draft, LMPCall, LMPSession
from capmj.agents.prompt_files import object_names
from capmj.agents.sandbox import SandboxBudget, extract_code
from capmj.errors import PlanError, describe
from capmj.llm.provider import derived_seed

__all__ = ["DEFAULT_PLAN_BUDGET", "MAX_REPLAN_TEMPERATURE", "REPLAN_TEMPERATURE_STEP", "Feedback", "PlanOutcome",
           "Sampling", "build_messages", "feedback_text", "fresh_messages", "identical_text", "plan_and_run", "plan_key",
           "replan_sampling"]

DEFAULT_PLAN_BUDGET = SandboxBudget(wall_s=60.0, max_api_calls=2000, max_lines=100_000)
"""Deterministic: 100 000 executed lines (loop iterations included), 2000 API calls, the
sandbox's element caps; physics is budgeted in simulation steps and primitives by the episode
context.  The wall time is a backstop for the plan's own Python only: time inside API functions
(simulation, helper LMP calls waiting on the LLM) is not counted."""


REPLAN_TEMPERATURE_STEP = 0.3
"""How much each retry after an identical re-plan raises the temperature (see :func:`replan_sampling`)."""
MAX_REPLAN_TEMPERATURE = 1.5
"""Retries never sample hotter than this (unless the re-plan temperature itself is higher)."""


@dataclass(frozen=True)
class Sampling:
    """How one planner request samples: its temperature and seed."""

    temperature: float
    seed: int


def replan_sampling(base: float, episode_seed: int, attempt: int, retry: int) -> Sampling:
    """The sampling of request ``retry`` (0: the first request; 1, 2, ...: the retries after an
    identical answer) of the planner in re-plan ``attempt`` (2, 3, ...).

    The temperature is ``base`` (``--replan-temperature``) + :data:`REPLAN_TEMPERATURE_STEP` per
    retry, at most :data:`MAX_REPLAN_TEMPERATURE`.  Why rising: a small model copies the previous
    plan shown in the re-plan prompt even at ``--replan-temperature`` (``docs/llm.md``, "Re-plans
    that differ"); that copy is so likely that sampling the same distribution again mostly draws
    it again, and flattening the distribution is what makes another plan reachable.  Why capped:
    much above the cap a small model's code turns to noise (misspelt API names, unbalanced
    brackets), which fails as surely as a copy.

    The seed (the OpenAI ``seed`` parameter) is derived from the episode seed, the attempt and the
    retry alone.  Why: without one, llama.cpp and other servers draw a random seed per request, so
    a run could not be repeated; with it, a server that honours ``seed`` answers the same request
    the same way (and the LLM cache key includes it), while each retry still draws anew
    (:func:`capmj.llm.provider.derived_seed`).
    """
    temperature = min(base + REPLAN_TEMPERATURE_STEP * retry, max(base, MAX_REPLAN_TEMPERATURE))
    return Sampling(round(temperature, 3), derived_seed(f"capmj-replan/{int(episode_seed)}/{int(attempt)}/{int(retry)}"))


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
    from_initial: bool = True
    """The plan ran from the episode's initial scene (False: from where an earlier plan left it)."""
    reset: bool = True
    """The next plan starts from the initial scene (False: the ``careful`` loop keeps the scene)."""


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
    """The earliest earlier attempt whose plan equals the final answer's (None: it differs)."""
    first_identical_to: int | None = None
    """Same for the first answer, when it was identical and a different plan was asked for."""
    extra_requests: int = 0
    """Requests made because an answer was identical to an earlier attempt's plan."""
    temperatures: list[float | None] = field(default_factory=list)
    """Temperature of each planner request, in order (None: the client's configured one)."""
    seeds: list[int | None] = field(default_factory=list)
    """Sampling seed of each planner request, in order (None: none sent)."""
    not_run: str | None = None
    """Why the plan was not run (still identical to an earlier attempt's after the retries), else None."""


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


def _failure(feedback: Feedback) -> list[str]:
    """What went wrong in an attempt: its failing line, its error, the reporter's verdict."""
    out = []
    lines = feedback.code.rstrip("\n").splitlines() if feedback.code else []
    if feedback.error_line is not None and 1 <= feedback.error_line <= len(lines):
        out.append(f"# It failed at line {feedback.error_line}: {lines[feedback.error_line - 1].strip()}")
    if feedback.error:
        out += _comment(f"Error: {feedback.error}")
    if feedback.report:
        out += _comment(feedback.report)
    return out


def feedback_text(feedback: Feedback) -> str:
    """The comment block of a re-plan request (without the question)."""
    start = "the initial scene" if feedback.from_initial else "the scene the previous plan left"
    out = [f"# The plan above (attempt {feedback.attempt}) ran from {start} and did not achieve the goal."]
    if feedback.code:
        lines = feedback.code.rstrip("\n").splitlines()
        width = len(str(len(lines)))
        out.append("# The plan as it ran, with line numbers:")
        out += [f"# {i:>{width}}| {line}" for i, line in enumerate(lines, start=1)]
    out += _failure(feedback)
    if feedback.scene:
        out += _comment(feedback.scene)
    if feedback.reset:
        out.append("# The scene has been reset to its initial state. Write a corrected complete plan for the same goal: "
                   "fix what went wrong, do not repeat the plan above.")
    else:
        out.append("# The scene has NOT been reset: every object is where the plan above left it (positions above). "
                   "Write a plan that, from this scene, fixes only the objects whose state is wrong; leave the others "
                   "where they are.")
    return "\n".join(out)


def identical_text(attempt: int, failed: Feedback | None) -> str:
    """The comment block of a retry after an answer identical to the plan of ``attempt``; its
    failure (``failed``: that attempt's feedback, when known) is shown again."""
    out = [f"# The plan above is identical to the plan of attempt {attempt}, which did not achieve the goal."]
    out += _failure(failed) if failed is not None else []
    out.append("# Running it again would fail the same way. Write a different complete plan: change at least "
               f"the lines that caused the failure of attempt {attempt}.")
    return "\n".join(out)


def fresh_messages(session: LMPSession, goal: str, attempt: int, failed: Feedback | None) -> list[dict[str, Any]]:
    """A retry's conversation that does not contain the plan it keeps repeating: the planner prompt
    with the goal, followed by what went wrong in ``attempt`` (failing line, error, verdict).

    Why: with the failed plan in the conversation (as the re-plan request must show it), a small
    model copies it even at a high temperature; without it the model writes the plan anew, warned
    about the failure (``docs/llm.md``, "Re-plans that differ")."""
    hint = [f"# An earlier plan for this goal (attempt {attempt}) did not achieve it."]
    hint += _failure(failed) if failed is not None else []
    hint.append("# Write a complete plan that avoids that failure.")
    q = f"{question(session.objects_text(), goal)}\n" + "\n".join(hint)
    return session.messages(session.prompt("planner").render(q))


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
                 outcome: PlanOutcome | None = None, retries: int = 0,
                 sampling: Callable[[int], Sampling] | None = None, earlier: Sequence[Feedback] = ()
                 ) -> PlanOutcome:
    """Ask for a plan and run it.  Raises LLMError (provider) or PlanError (code); ``outcome``
    (when given) holds the completion and executed code even then.

    ``previous`` are the :func:`plan_key` of the plans of attempts 1, 2, ...; an answer equal to
    one of them is asked again, up to ``retries`` times, showing that attempt's failure again (its
    :class:`Feedback` among ``earlier``, else ``feedback``): the first retry in the conversation,
    later ones in a fresh conversation without the repeated plan (:func:`fresh_messages`).  ``sampling(r)`` gives request r's
    temperature and seed (r = 0 the first request; without it the client's own are used).  A plan
    still identical after the retries is not run (``outcome.not_run`` says why)."""
    out = outcome if outcome is not None else PlanOutcome()

    def ask(call: LMPCall, messages: list[dict[str, Any]]) -> str:
        chosen = sampling(len(out.temperatures)) if sampling is not None else None
        out.temperatures.append(chosen.temperature if chosen is not None else None)
        out.seeds.append(chosen.seed if chosen is not None else None)
        if chosen is None:
            return session.ask(call, messages)
        return session.ask(call, messages, temperature=chosen.temperature, seed=chosen.seed)

    def same_as(key: str) -> int | None:
        return list(previous).index(key) + 1 if key in previous else None

    call = session.next_call("planner", goal)
    out.call = call
    messages = build_messages(session, goal, feedback)
    out.completion = ask(call, messages)
    out.key = plan_key(out.completion)
    identical = out.first_identical_to = same_as(out.key)
    while identical is not None and out.extra_requests < retries:
        out.extra_requests += 1
        session.recorder.text(f"llm/attempt{session.attempt}/planner/{call.n}/identical_to",
                              f"identical to the plan of attempt {identical}; asking for a different plan "
                              f"(retry {out.extra_requests} of {retries})")
        failed = next((f for f in earlier if f.attempt == identical), feedback)
        if out.extra_requests == 1:  # first retry: in the conversation, pointing at the copy
            again = messages + [
                {"role": "assistant", "content": out.completion},
                {"role": "user", "content": f"{identical_text(identical, failed)}\n{question(session.objects_text(), goal)}\n"},
            ]
        else:  # later retries: a fresh conversation without the plan to copy
            again = fresh_messages(session, goal, identical, failed)
        call = out.call = session.next_call("planner", goal)
        out.completion = ask(call, again)
        out.key = plan_key(out.completion)
        identical = same_as(out.key)
    out.identical_to = identical
    if identical is not None:
        out.not_run = f"identical to attempt {identical} after {out.extra_requests} retries; not re-run"
        try:
            out.code = extract_code(out.completion)
        except PlanError:
            out.code = None
        session.record(call, "result", f"plan not run: {out.not_run}")
        return out
    env = session.plan_env()
    env["objects"] = object_names(session.objects_text()) or []
    env["goal"] = goal
    draft = Draft()
    try:
        session.run_answer(call, out.completion, env, filename=f"<plan attempt {session.attempt}>", program="the plan",
                           budget=budget, rng=session.rng, output=out.output, draft=draft)
    except PlanError as exc:
        session.record(call, "error", describe(exc))
        raise
    finally:
        out.code = draft.code if draft.code is not None else out.code
        if out.output:
            session.recorder.text(f"llm/attempt{session.attempt}/planner/{call.n}/printed", "\n".join(out.output))
    session.record(call, "result", "plan finished")
    return out
