"""The ``relations`` text-reporter prompt: the model names the relations the goal asks for, as
calls of capmj's pre-bound checks, and capmj measures them on the final and the start scene.

The question holds only the goal and the inventory (the keys acting cannot change), so the answer
is written before the result is seen.  The answer is calls such as
``require_inside(blocks(color="red"), zone("green"))`` (:mod:`capmj.agents.report.relations.checks`);
the verdict is "achieved" exactly when no call failed, and ``wrong`` is the objects the failed
calls name, so a "not achieved" always names movable objects.  The prompt is
``prompts/reporter_relations.py``.

Each answer gets one repair request when it tests nothing or cannot be right.  The gates run in
this order, and the first that finds a problem decides:

* it calls a name the prompt does not define (:class:`~capmj.errors.UnknownCheckError`, naming the
  valid ones; never a function written by ``parse_function``) or no ``require_*`` at all
  (:data:`BLIND`).  Still so after the repair: the ``checked`` question as ``direct``
  (:class:`~capmj.agents.report.records.RecordsReporter`);
* a group required as one tower and in layers of several is read as layers, the tower asking only
  for its place (:data:`LAYERED`): not a problem, a reading;
* its calls contradict each other, so no scene could pass them (:data:`IMPOSSIBLE`,
  :meth:`~capmj.agents.report.relations.checks.Failures.impossible`): ``impossible_check``;
* it picks a block colour or a count the goal does not give
  (:func:`~capmj.agents.report.relations.grounding.ungrounded`): ``ungrounded_literal``;
* its calls all pass on the start scene (:data:`HOLDS_AT_START`, with the first pick that found no
  block): ``holds_at_start``;
* it never asks for a relation the goal names
  (:func:`~capmj.agents.report.relations.coverage.uncovered`): ``misses_a_relation``.

Still so after the repair, the last four keep their verdict, low-confidence under their key.  Why
each gate exists: ``docs/judge.md``, "Why each gate exists".
"""

from __future__ import annotations

import ast
import dataclasses
from typing import Any

from capmj.agents.lmp.codeprep import named_calls, undefined_calls
from capmj.agents.lmp.session import LMPCall, LMPSession
from capmj.agents.report.relations.checks import CHECKS, NAMES, SELECTORS, Failures, relation_env
from capmj.agents.report.relations.coverage import uncovered
from capmj.agents.report.relations.grounding import ungrounded
from capmj.agents.report.records import RecordsReporter
from capmj.agents.sandbox import extract_code, run_code
from capmj.agents.report.scene_records import INVENTORY_KEYS, records, records_text
from capmj.agents.report.verdict import CheckRun
from capmj.errors import PlanError, UnknownCheckError, describe

__all__ = ["BLIND", "HOLDS_AT_START", "IMPOSSIBLE", "LAYERED", "PROMPT", "RelationsReporter"]

PROMPT = "reporter_relations"
"""The prompt file (``prompts/reporter_relations.py``) and the LMP name in transcripts."""

BLIND = "it calls none of the require_... checks, so it tests nothing: call the checks the goal asks for"
"""The problem the repair request states when the answer makes no ``require_*`` call."""

HOLDS_AT_START = ("every require_... call passes in the scene the robot started from, and no goal holds there: "
                  "require what the goal asks the robot to achieve (where the objects must be, stacks, layers ...)")
"""The problem the repair request states when the check finds nothing wrong with the start scene."""

LAYERED = ("require_stack of objects also required in layers of several is read as their place only: "
           "a structure with several blocks in a layer is require_layers")
"""The transcript note when a tower call is read as its place (:meth:`~capmj.agents.report.relations.checks.Failures.layered_towers`)."""

IMPOSSIBLE = "no arrangement of the objects could pass every require_... call, so it says \"not achieved\" of every scene"
"""The start of the problem the repair request states when the calls contradict each other."""


def calls_a_check(code: str) -> bool:
    """Whether ``code`` calls one of :data:`~capmj.agents.report.relations.checks.CHECKS` (read with :mod:`ast`)."""
    try:
        tree = ast.parse(code)
    except SyntaxError:
        return True  # the sandbox reports it
    return any(name in CHECKS for name, _ in named_calls(tree))


class RelationsReporter(RecordsReporter):
    """``--reporter-prompt relations``: the goal as calls of pre-bound relation checks (see the module docstring)."""

    prompt = "relations"
    prompt_file = PROMPT

    def question(self, session: LMPSession, ctx: Any, goal: str) -> str:
        """The scene's inventory (the keys acting cannot change) and the goal."""
        inventory = records_text(self._records(session, ctx), INVENTORY_KEYS)
        return f"# The objects of this scene.\n{inventory}\n# goal: {' '.join(goal.split())}"

    def repair_request(self, goal: str) -> str:
        return (f"# Write the corrected complete check for the same goal: only calls of {', '.join(CHECKS)} "
                f"on objects picked with {', '.join(SELECTORS)}. Do not set judge.\n# goal: {' '.join(goal.split())}\n")

    def _run(self, session: LMPSession, call: LMPCall, code: str, rows: list[dict[str, Any]],
             start: list[dict[str, Any]] | None, scene: str, label: str,
             layered: frozenset[frozenset[str]] = frozenset()) -> tuple[CheckRun, Failures | None]:
        """Run prepared ``code`` on one scene's records (``start``: the start scene's, for ``require_unmoved``;
        ``layered``: see :func:`relation_env`): the verdict is that no required relation failed, and what its
        calls asked for (None when it failed to run)."""
        env, failures = relation_env(rows, start, layered)
        failed = "error" if label == "result" else f"{label} error"
        try:
            run_code(code, env, budget=session.lmp_budget,
                     filename=f"<{self.prompt_file} {session.attempt}.{call.n}{scene}>")
        except PlanError as exc:
            problem = describe(exc)
            session.record(call, failed, problem)
            return CheckRun(None, problem=problem, code=code), None
        verdict = not failures.items
        session.record(call, label, f"judge = {verdict!r}\nreason = {failures.reason!r}\nwrong = {list(failures.wrong)!r}")
        return CheckRun(verdict, failures.reason, failures.wrong, None, code), failures

    def _check(self, session: LMPSession, call: LMPCall, text: str, ctx: Any, goal: str, last: bool) -> CheckRun:
        rows = self._records(session, ctx)
        start = records(self._start_state, self._start) if self._start_state is not None else None
        known = set(NAMES)
        code = ""
        try:
            code = extract_code(text)
            missing = [m[0] for m in undefined_calls(code, known)]
            if missing:
                raise UnknownCheckError(f"{', '.join(missing)} is not defined; the checks are {', '.join(CHECKS)} "
                                        f"and the selectors {', '.join(SELECTORS)}")
            code = session.prepare(code, dict.fromkeys(known), parent=call)  # drops benign imports only
            session.record(call, "code", code)
        except PlanError as exc:
            problem = describe(exc)
            session.record(call, "error", problem)
            return CheckRun(None, problem=problem, code=code)
        if not calls_a_check(code):
            session.record(call, "blind", BLIND)
            return CheckRun(None, problem=BLIND, code=code)
        run, asked = self._run(session, call, code, rows, start, "", "result")
        layered = asked.layered_towers() if asked is not None else frozenset()
        if layered:
            session.record(call, "layered", LAYERED)
            run, asked = self._run(session, call, code, rows, start, "", "result", layered)
        if run.problem is not None or asked is None:
            return run

        def doubted(key: str, problem: str, label: str | None) -> CheckRun:
            """A check that cannot be right: its problem for the repair request, or after the repair its
            verdict, kept low-confidence (``key``); ``label``: the transcript entry (None: its run's says it)."""
            if label is not None:
                session.record(call, label, problem)
            return dataclasses.replace(run, doubt=key) if last else CheckRun(None, problem=problem, code=code)

        impossible = asked.impossible()
        if impossible is not None:
            return doubted("impossible_check", f"{IMPOSSIBLE}: {impossible}", "impossible")
        guessed = ungrounded(code, goal, rows)
        if guessed is not None:
            return doubted("ungrounded_literal", guessed, "ungrounded")
        if start is not None and self._run(session, call, code, start, start, " start", "start scene",
                                           layered)[0].verdict:
            return doubted("holds_at_start", HOLDS_AT_START + "".join(f"; {pick}" for pick in asked.empty_picks[:1]),
                           None)
        unasked = uncovered(code, goal)
        if unasked is not None:
            return doubted("misses_a_relation", unasked, "uncovered")
        return run
