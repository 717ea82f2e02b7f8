"""The text reporter (``--reporter text``, the ``thesis`` prompt): the ``parse_completion`` LMP writes
checking code over the settled scene, and :func:`plan_check` is the same reporter as the
``parse_completion`` a plan may call.

The code sets ``judge`` (bool), ``reason`` and optionally ``wrong`` (names of the objects whose
state is wrong); it runs in the sandbox with the read-only API plus the pre-bound names of
:mod:`capmj.agents.report.text_env` (``poses``, ``sizes``, ``goal_objects``, ``in_zone`` ...), so a
completion that drops its first line still runs.  It runs the reporters' one loop
(:func:`~capmj.agents.report.verdict.ask_for_verdict`): code, one repair quoting the error and its
line, then the direct question.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from capmj.agents.base import JUDGE_SETTLE_STEPS
from capmj.agents.lmp.session import Draft, LMPCall, LMPSession
from capmj.agents.report.text_env import PREBOUND, reporter_env
from capmj.agents.report.verdict import (Answer, Gate, Reading, Report, ask_for_verdict, direct_verdict, names_of,
                                         record_reading)
from capmj.errors import PlanError, describe

__all__ = ["TextReporter", "failing_line", "plan_check", "reading_of"]


def failing_line(exc: PlanError, code: str) -> str:
    """A new line quoting ``line N: <source>`` of ``code`` when the error has a line, else ``""``."""
    lines = code.splitlines()
    if exc.line is None or not 1 <= exc.line <= len(lines):
        return ""
    return f"\n    line {exc.line}: {lines[exc.line - 1].strip()}"


def reading_of(namespace: Mapping[str, Any]) -> Reading:
    """The verdict checking code left in its namespace: a bool ``judge``, ``reason``, ``wrong``."""
    judge, reason = namespace.get("judge"), namespace.get("reason")
    reason = reason if isinstance(reason, str) else ""
    if not isinstance(judge, (bool, np.bool_)):
        problem = ("the code did not set 'judge'" if "judge" not in namespace
                   else f"'judge' is {type(judge).__name__} {str(judge)[:80]!r}, not True or False")
        return Reading(None, reason, problem=problem)
    return Reading(bool(judge), reason, names_of(namespace.get("wrong")))


def _repair_request(problem: str, question: str) -> str:
    return (f"# The checking code above failed: {problem}\n"
            f"# Write the corrected complete checking code for the same goal. Already defined (do not "
            f"redefine them): {', '.join(PREBOUND)}.\n"
            "# Set judge = True or False, reason = a short explanation, wrong = [names of the objects whose "
            "state is wrong].\n" + question + "\n")


class TextReporter:
    """``parse_completion`` over the settled scene: code, one repair, then the direct verdict."""

    mode = "text"
    gates: tuple[Gate[Any], ...] = ()

    def __init__(self, prompt_directory: Any = None) -> None:
        """``prompt_directory`` is the session's too: its prompt is read through the session."""

    def start(self, ctx: Any) -> None:  # nothing to capture before acting
        return None

    def judge(self, session: LMPSession, ctx: Any, goal: str) -> Report:
        sentence = " ".join(goal.split())
        sentence = sentence if sentence.endswith((".", "?", "!")) else sentence + "."
        question = f"{session.objects_text().strip()}\n# goal: {sentence}"

        def read(call: LMPCall, answer: Answer, last: bool) -> Reading:
            env = session.helper_env(question)
            env.update(reporter_env(session.api, ctx.world.objects, goal))  # fresh: code may mutate it
            draft = Draft()
            try:
                namespace = session.run_answer(call, answer.text, env, draft=draft,
                                               filename=f"<parse_completion {session.attempt}.{call.n}>")
            except PlanError as exc:
                return record_reading(session, call, Reading(None, problem=describe(exc) + failing_line(
                    exc, draft.code or "")))
            return record_reading(session, call, reading_of(namespace))

        return ask_for_verdict(
            session, self.mode, session.messages(session.prompt("parse_completion").render(question)),
            call=lambda source: session.next_call("parse_completion", goal), read=read,
            repair=lambda answer, problem: _repair_request(problem, question),
            fallback=lambda errors: direct_verdict(session, goal, self.mode, errors))

    def close(self) -> None:
        return None


def plan_check(session: LMPSession, ctx: Any) -> Callable[..., bool]:
    """The ``parse_completion(goal, context=None)`` function of one attempt's plan.

    CapRavens' plans check their own work and retry (``if not parse_completion(...): reset()``).
    This one lets the world come to rest, as before any verdict, runs :class:`TextReporter` on the
    scene as it is now and returns its verdict as a bool.  ``context`` is accepted and not needed
    (the reporter reads the same live poses); an unknown verdict is False (the plan's retry branch
    runs).  Its calls are in the transcript and the log; its verdict never stands in for the one
    the agent asks for after the plan."""
    reporter = TextReporter()
    count = 0

    def parse_completion(goal: Any, context: Any = None) -> bool:
        """Whether ``goal`` is achieved in the scene as it is now (the text reporter's verdict)."""
        nonlocal count
        session.helper_cap.take("parse_completion")
        count += 1
        ctx.world.settle(max_steps=JUDGE_SETTLE_STEPS)
        report = reporter.judge(session, ctx, str(goal))
        verdict = report.verdict is True
        session.recorder.text(f"llm/attempt{session.attempt}/plan_check/{count}",
                              f"goal: {' '.join(str(goal).split())}\nverdict: {report.verdict!r} "
                              f"(from {report.source}) -> {verdict}\nreason: {report.reason}", ctx.world.time)
        return verdict

    return parse_completion
