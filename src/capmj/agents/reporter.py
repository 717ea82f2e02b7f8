"""Reporters: after a plan ran, judge whether the goal is achieved (and explain why not).

Two modes, as in CapRavens:

* **text** — the ``parse_completion`` LMP writes checking code over the settled scene that sets
  ``judge`` (bool), ``reason`` and optionally ``wrong`` (names of the objects whose state is
  wrong); the code runs in the sandbox with the read-only API plus the pre-bound names of
  :mod:`capmj.agents.reporter_env` (``poses``, ``sizes``, ``goal_objects``, ``in_zone`` ...), so a
  completion that drops its first line still runs.  :class:`TextReporter`, here.
* **vlm** — a vision-language model judges front-camera images (:mod:`capmj.agents.reporter_vlm`).

What a verdict is, where it came from (``code``, ``repair``, ``direct``, ``unknown``) and how it is
read from an answer: :mod:`capmj.agents.verdict`.  :func:`make_reporter` builds a reporter by name.
"""

from __future__ import annotations

from typing import Any

from capmj.agents.choices import REPORTER_PROMPTS, REPORTERS
from capmj.agents.lmp.session import LMPCall, LMPSession
from capmj.agents.reporter_checked import CheckedReporter
from capmj.agents.reporter_env import PREBOUND, reporter_env
from capmj.agents.reporter_goalcheck import GoalCheckReporter
from capmj.agents.reporter_relations import RelationsReporter
from capmj.agents.reporter_records import RecordsReporter
from capmj.agents.reporter_vlm import VLMReporter
from capmj.agents.verdict import CheckRun, Report, check, direct_verdict, parse_verdict
from capmj.errors import ConfigError

# Re-exported: Report and parse_verdict (tests import them from here), VLMReporter (make_reporter's).
__all__ = ["Report", "TextReporter", "VLMReporter", "make_reporter", "parse_verdict"]


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


def make_reporter(mode: str, prompt_directory: Any = None, prompt: str = "thesis") -> Any:
    """The reporter of ``mode`` (None for ``none``); ``prompt`` selects the text reporter's prompt."""
    if prompt not in REPORTER_PROMPTS or (prompt != "thesis" and mode == "vlm"):
        raise ConfigError(f"reporter prompt {prompt!r}: valid: {', '.join(REPORTER_PROMPTS)} (not thesis: text only)")
    if mode == "none":
        return None
    if mode == "text" and prompt == "checked":
        return CheckedReporter(prompt_directory)
    if mode == "text" and prompt == "records":
        return RecordsReporter(prompt_directory)
    if mode == "text" and prompt == "goalcheck":
        return GoalCheckReporter(prompt_directory)
    if mode == "text" and prompt == "relations":
        return RelationsReporter(prompt_directory)
    if mode == "text":
        return TextReporter()
    if mode == "vlm":
        return VLMReporter(prompt_directory)
    raise ConfigError(f"unknown reporter {mode!r}; valid reporters: {', '.join(REPORTERS)}")
