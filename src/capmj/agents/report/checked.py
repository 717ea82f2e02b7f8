"""The ``checked`` text-reporter prompt: capmj binds the scene facts, the model only compares.

One request with ``prompts/reporter_checked.txt``, which lists the facts
:mod:`capmj.agents.report.scene` measured with the tasks' own rules (per object: centre, quarter of
the table, what it rests on, the zone or bowl it is in, tilt) and asks for ``judge``, ``reason``
and ``wrong`` — the full names of the objects that break the goal.  The answer is parsed, never
executed; it runs the reporters' one loop (:func:`~capmj.agents.report.verdict.ask_for_verdict`):
no verdict, one repair request; still none, unknown (no ``direct`` fallback: this prompt already
is a direct question).  Its one gate, :data:`COPIES_EXAMPLE`, doubts a reason that is the prompt's
own example word for word.  It is also the ``relations`` reporter's fallback.
"""

from __future__ import annotations

from typing import Any

from capmj.agents.lmp.session import LMPCall, LMPSession
from capmj.agents.prompt_files import prompts_dir
from capmj.agents.report.scene import facts_text, scene_facts, state_from_api
from capmj.agents.report.verdict import Answer, Gate, Reading, Report, ask_for_verdict, gated, literal_reading
from capmj.errors import ConfigError

__all__ = ["COPIES_EXAMPLE", "PROMPT_FILE", "CheckedReporter"]

PROMPT_FILE = "reporter_checked.txt"

MIN_COPIED_CHARS = 20
"""A reason at least this long found word for word in the prompt file is its example copied
(shorter ones, such as "all blocks are in place", can match by chance)."""


def _copies(subject: tuple[str, str]) -> str | None:
    reason, template = subject
    reason = " ".join(reason.split())
    copied = len(reason) >= MIN_COPIED_CHARS and reason in " ".join(template.split())
    return "its reason is the prompt's own example, word for word" if copied else None


COPIES_EXAMPLE: Gate[tuple[str, str]] = Gate(
    "copies_example", None, "its reason is the prompt's own example, word for word", _copies, repairs=False)
"""A reason that is the prompt file's own example says nothing of the scene: doubted at once (on
``(reason, template)``)."""


class CheckedReporter:
    """The text reporter with capmj-computed facts (``--reporter-prompt checked``)."""

    mode = "text"
    prompt = "checked"
    gates: tuple[Gate[Any], ...] = (COPIES_EXAMPLE,)

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

        def read(call: LMPCall, answer: Answer, last: bool) -> Reading:
            got = literal_reading(session, call, answer)
            return got if got.problem is not None else gated(session, call, self.gates, (got.reason, template), got,
                                                             last)

        return ask_for_verdict(
            session, self.mode, session.messages(self.question(session, ctx, goal, template)),
            call=lambda source: session.next_call("reporter_checked", goal), read=read,
            repair=lambda answer, problem: (
                f"Your answer gave no verdict: {problem}. Answer only with one ```python block that sets judge = True "
                "or False, reason = a short explanation and wrong = [full names of the objects whose facts break the "
                "goal]."),
            fallback=lambda errors: Report(self.mode, None, "", errors[-1], "unknown", (), errors))

    def close(self) -> None:
        return None
