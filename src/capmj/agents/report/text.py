"""The text reporter: the ``parse_completion`` LMP writes checking code over the settled scene.

The code sets ``judge`` (bool), ``reason`` and optionally ``wrong`` (names of the objects whose
state is wrong); it runs in the sandbox with the read-only API plus the pre-bound names of
:mod:`capmj.agents.report.text_env` (``poses``, ``sizes``, ``goal_objects``, ``in_zone`` ...), so a
completion that drops its first line still runs.  :class:`TextReporter` is the ``thesis`` prompt of
``--reporter text``; the other reporters and how one is chosen by name are in
:mod:`capmj.agents.report` (the vision-language one: :mod:`capmj.agents.report.vlm`).

What a verdict is, where it came from (``code``, ``repair``, ``direct``, ``unknown``) and how it is
read from an answer: :mod:`capmj.agents.report.verdict`.
"""

from __future__ import annotations

from typing import Any

from capmj.agents.lmp.session import LMPCall, LMPSession
from capmj.agents.report.text_env import PREBOUND, reporter_env
from capmj.agents.report.verdict import CheckRun, Report, check, direct_verdict

__all__ = ["TextReporter"]


def _repair_request(problem: str, question: str) -> str:
    return (f"# The checking code above failed: {problem}\n"
            f"# Write the corrected complete checking code for the same goal. Already defined (do not "
            f"redefine them): {', '.join(PREBOUND)}.\n"
            "# Set judge = True or False, reason = a short explanation, wrong = [names of the objects whose "
            "state is wrong].\n" + question + "\n")


# ------------------------------------------------------------------------------------------------
# text reporter
# ------------------------------------------------------------------------------------------------
class TextReporter:
    """``parse_completion`` over the settled scene: code, one repair, then the direct verdict."""

    mode = "text"

    def __init__(self, prompt_directory: Any = None) -> None:
        """``prompt_directory`` is the session's too: its prompt is read through the session."""

    def start(self, ctx: Any) -> None:  # nothing to capture before acting
        return None

    def judge(self, session: LMPSession, ctx: Any, goal: str) -> Report:
        sentence = " ".join(goal.split())
        sentence = sentence if sentence.endswith((".", "?", "!")) else sentence + "."
        question = f"{session.objects_text().strip()}\n# goal: {sentence}"
        messages = session.messages(session.prompt("parse_completion").render(question))
        errors: tuple[str, ...] = ()
        for source in ("code", "repair"):
            call = session.next_call("parse_completion", goal)
            text = session.ask(call, messages)
            run = self._run(session, call, text, ctx, goal, question)
            problem = run.problem
            if problem is None:
                return Report(self.mode, run.verdict, run.reason, errors[-1] if errors else None, source, run.wrong,
                              errors)
            errors += (f"{source}: {problem}",)
            messages = messages + [{"role": "assistant", "content": text},
                                   {"role": "user", "content": _repair_request(problem, question)}]
        return direct_verdict(session, goal, self.mode, errors)

    @staticmethod
    def _run(session: LMPSession, call: LMPCall, text: str, ctx: Any, goal: str, question: str) -> CheckRun:
        """The run of one answer's checking code."""
        env = session.helper_env(question)
        env.update(reporter_env(session.api, ctx.world.objects, goal))  # fresh: code may mutate it
        return check(session, call, text, env, f"<parse_completion {session.attempt}.{call.n}>")

    def close(self) -> None:
        return None
