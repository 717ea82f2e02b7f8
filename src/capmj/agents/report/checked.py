"""The ``checked`` text-reporter prompt: capmj binds the scene facts, the model only compares.

``--reporter-prompt thesis`` (the default) is the thesis's text reporter,
:class:`~capmj.agents.report.text.TextReporter`: the ``parse_completion`` LMP writes checking code that
must itself derive positions, containment and stacking.  ``--reporter-prompt checked`` is
:class:`CheckedReporter`: one request with ``prompts/reporter_checked.txt``, which lists the facts
:mod:`capmj.agents.report.scene_facts` measured with the tasks' own rules (per object: centre, quarter of
the table, what it rests on, the zone or bowl it is in, tilt) and asks for ``judge``, ``reason``
and ``wrong`` — the full names of the objects that break the goal.

The answer is parsed with :mod:`ast`, never executed (:func:`~capmj.agents.report.verdict.parse_verdict`).
An answer without a verdict gets one repair request in the same conversation; still none: unknown.
Sources: ``code`` (the first answer's code block), ``repair``, ``unknown`` — no ``direct`` fallback,
since this prompt already is a direct question.  Whether the verdict can be trusted (does it name
real objects?) is :func:`capmj.agents.report.confidence.assess`, applied to either prompt's verdict.

A verdict whose reason is the prompt file's own example word for word is marked
``doubt="copies_example"`` (low confidence): it says nothing of the scene.  Why this prompt and
this gate exist: ``docs/judge.md``, "Why each gate exists".
"""

from __future__ import annotations

import dataclasses
from typing import Any

from capmj.agents.lmp.session import LMPSession
from capmj.agents.prompt_files import prompts_dir
from capmj.agents.report.verdict import Report, ask_verdict
from capmj.agents.report.scene_facts import facts_text, scene_facts, state_from_api
from capmj.errors import ConfigError

__all__ = ["PROMPT_FILE", "CheckedReporter"]

PROMPT_FILE = "reporter_checked.txt"

MIN_COPIED_CHARS = 20
"""A reason at least this long found word for word in the prompt file is its example copied
(shorter ones, such as "all blocks are in place", can match by chance)."""


class CheckedReporter:
    """The text reporter with capmj-computed facts (``--reporter-prompt checked``)."""

    mode = "text"
    prompt = "checked"

    def __init__(self, prompt_directory: Any = None) -> None:
        self.directory = prompt_directory

    def start(self, ctx: Any) -> None:  # nothing to capture before acting
        return None

    def template(self, session: LMPSession) -> str:
        """The prompt file's text, with its ``<<FACTS>>`` and ``<<GOAL>>`` slots."""
        folder = self.directory if self.directory is not None else (
            session.directory if session.directory is not None else prompts_dir())
        try:
            return (folder / PROMPT_FILE).read_text(encoding="utf-8")
        except FileNotFoundError:
            raise ConfigError(f"checked reporter prompt {folder / PROMPT_FILE} not found") from None

    def question(self, session: LMPSession, ctx: Any, goal: str, template: str | None = None) -> str:
        """The prompt: the template (read when not given) with the measured facts and the goal filled in."""
        facts = scene_facts(state_from_api(session.api, ctx.world.objects))
        text = self.template(session) if template is None else template
        return text.replace("<<FACTS>>", facts_text(facts)).replace("<<GOAL>>", " ".join(goal.split()))

    def judge(self, session: LMPSession, ctx: Any, goal: str) -> Report:
        template = self.template(session)
        messages = session.messages(self.question(session, ctx, goal, template))
        report, errors = ask_verdict(
            session, self.mode, lambda source: session.next_call("reporter_checked", goal), messages,
            "Answer only with one ```python block that sets judge = True or False, reason = a short explanation and "
            "wrong = [full names of the objects whose facts break the goal].")
        if report is None:
            return Report(self.mode, None, "", errors[-1], "unknown", (), errors)
        reason = " ".join(report.reason.split())
        if len(reason) >= MIN_COPIED_CHARS and reason in " ".join(template.split()):
            return dataclasses.replace(report, doubt="copies_example")
        return report

    def close(self) -> None:
        return None
