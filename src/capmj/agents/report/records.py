"""The ``records`` text-reporter prompt: capmj binds the measured facts as records, the model
writes checking code over them, and the code runs in the sandbox.

The facts of :mod:`capmj.agents.report.scene_facts` become a Python list of dicts
(:mod:`capmj.agents.report.scene_records`), the prompt (``prompts/reporter_records.py``) documents
the keys and shows three short checks, and the model writes code that sets ``judge``, ``reason``
and ``wrong``.  The code runs in the sandbox like every other model-written code
(:func:`capmj.agents.report.verdict.check`), with one repair request on failure.  Still no
verdict: the ``checked`` question (:class:`~capmj.agents.report.checked.CheckedReporter`, the same
measured facts, a literal answer parsed and never run) is asked as the ``direct`` source, never
the ``thesis`` direct prompt (it asks the model to derive the facts again from poses).  A
``direct`` verdict is recorded and scored, but low-confidence
(:func:`capmj.agents.report.confidence.assess`): the ``careful`` loop does not act on it.

The repair request of an answer that began by writing the records out again (``objects = [``)
says so in words (:data:`COPIED_RECORDS_HINT`).  It samples at :data:`REPAIR_TEMPERATURE` with a
seed derived from the question, so it can differ from the failed answer and still be repeated.
The prompt's stop sequences cut an answer that starts copying the records out
(``\n    {'name': ``).  Why each of these exists: ``docs/judge.md``, "Why each gate exists".
"""

from __future__ import annotations

import dataclasses
import re
from typing import Any

from capmj.agents.lmp.session import LMPCall, LMPSession
from capmj.agents.report.checked import CheckedReporter
from capmj.agents.report.scene_facts import state_from_api
from capmj.agents.report.scene_records import RECORD_KEYS, records, records_text, start_areas_of
from capmj.agents.report.verdict import CheckRun, Report, check
from capmj.llm.provider import derived_seed
from capmj.sim.state import SceneState

__all__ = ["PROMPT", "RecordsReporter"]

PROMPT = "reporter_records"
"""The prompt file (``prompts/reporter_records.py``) and the LMP name in transcripts."""

COPIED_RECORDS_HINT = ("# `objects` is already defined with the records above: do not write it out again. "
                       "Start with the first line of the check.\n")
"""Added to the repair request when the failed answer began by assigning ``objects``."""

_COPIES_RECORDS = re.compile(r"\A\s*(?:```[A-Za-z]*\s*)?objects\s*=")

REPAIR_TEMPERATURE = 0.7
"""Sampling temperature of the repair request (the first request uses the client's, default 0)."""


class RecordsReporter:
    """The text reporter with capmj-bound records and model-written checks (``--reporter-prompt records``)."""

    mode = "text"
    prompt = "records"
    prompt_file = PROMPT
    """The prompt file under ``prompts/`` and the LMP name in transcripts."""

    def __init__(self, prompt_directory: Any = None) -> None:
        self._start: dict[int, str] = {}
        self._start_state: SceneState | None = None
        self._fallback = CheckedReporter(prompt_directory)

    def start(self, ctx: Any) -> None:
        """Remember the start scene and the quarter each object starts in (the ``start_area`` of its record).

        Read from the simulator's initial state, as the episode's own start is known to any
        observer of it; in ``--perception rgbd`` mode this one fact is not perceived."""
        self._start_state = ctx.world.state()
        self._start = start_areas_of({o.obj_id: pose.pos for o, pose in self._start_state})

    def _records(self, session: LMPSession, ctx: Any) -> list[dict[str, Any]]:
        return records(state_from_api(session.api, ctx.world.objects), self._start)

    def question(self, session: LMPSession, ctx: Any, goal: str) -> str:
        """The scene's records and the goal, as the prompt's last lines."""
        return f"{records_text(self._records(session, ctx))}\n# goal: {' '.join(goal.split())}"

    def judge(self, session: LMPSession, ctx: Any, goal: str) -> Report:
        question = self.question(session, ctx, goal)
        messages = session.messages(session.prompt(self.prompt_file).render(question))
        errors: tuple[str, ...] = ()
        for source, sampling in (("code", {}), ("repair", {"temperature": REPAIR_TEMPERATURE,
                                                            "seed": derived_seed(f"capmj-records-repair/{question}")})):
            call = session.next_call(self.prompt_file, goal)
            text = session.ask(call, messages, **sampling)
            run = self._check(session, call, text, ctx, goal, last=source == "repair")
            problem = run.problem
            if problem is None:
                return Report(self.mode, run.verdict, run.reason, errors[-1] if errors else None, source, run.wrong,
                              errors, run.doubt)
            errors += (f"{source}: {problem}",)
            copied = COPIED_RECORDS_HINT if _COPIES_RECORDS.match(text) else ""
            messages = messages + [{"role": "assistant", "content": text}, {"role": "user", "content": (
                f"# The checking code above failed: {problem}\n{copied}{self.repair_request(goal)}")}]
        return self._direct(session, ctx, goal, errors)

    def repair_request(self, goal: str) -> str:
        """What the repair request asks for, after the problem it quotes."""
        return (f"# Write the corrected complete checking code for the same goal, using only `objects` (dicts with "
                f"keys {', '.join(RECORD_KEYS)}).\n# Set judge = True or False, reason = a short sentence, wrong = "
                f"[full names of the movable objects that break the goal].\n# goal: {' '.join(goal.split())}\n")

    def _check(self, session: LMPSession, call: LMPCall, text: str, ctx: Any, goal: str, last: bool) -> CheckRun:
        """The answer's check run on the scene's records (``goal``: the goal it checks).

        ``last``: no repair request follows, so a subclass keeps a doubtful verdict (``CheckRun.doubt``)
        instead of returning a problem."""
        env: dict[str, Any] = {"objects": self._records(session, ctx)}  # fresh: code may mutate it
        return check(session, call, text, env, f"<{self.prompt_file} {session.attempt}.{call.n}>")

    def _direct(self, session: LMPSession, ctx: Any, goal: str, errors: tuple[str, ...]) -> Report:
        """The ``checked`` question after two failed checks: its verdict, as source ``direct``."""
        report = self._fallback.judge(session, ctx, goal)
        errors += tuple(f"direct {e}" for e in report.errors)
        source = "unknown" if report.verdict is None else "direct"
        return dataclasses.replace(report, source=source, errors=errors, error=errors[-1])

    def close(self) -> None:
        return None
