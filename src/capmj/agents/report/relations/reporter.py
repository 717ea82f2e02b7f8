"""The ``relations`` text-reporter prompt: the model names the relations the goal asks for, as
calls of capmj's pre-bound checks, and capmj measures them on the final and the start scene.

The question holds only the goal and the inventory (the keys acting cannot change), so the answer
is written before the result is seen.  The answer is calls such as
``require_inside(blocks(color="red"), zone("green"))`` (:mod:`capmj.agents.report.relations.checks`);
the verdict is "achieved" exactly when no call failed, and ``wrong`` is the objects the failed
calls name.  The prompt is ``prompts/reporter_relations.py``.

It runs the reporters' one loop (:func:`~capmj.agents.report.verdict.ask_for_verdict`).  An answer
that calls a name the prompt does not define (:class:`~capmj.errors.UnknownCheckError`, naming the
valid ones) or fails to run gets the repair request; so does one that fails a gate, in this order:
:data:`BLIND_GATE` (before the run), then :data:`GATES` (``impossible_check``,
``ungrounded_literal``, ``holds_at_start``, ``misses_a_relation``).  A group required as one tower
and in layers of several is read as layers (:data:`LAYERED`, a reading, not a problem).  After the
repair, a blind answer or one that fails to run goes to the ``checked`` question as ``direct``;
the other gates keep its verdict, low-confidence under their key.  Why each gate exists:
``docs/judge.md``, "Why each gate exists".
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from capmj.agents.lmp.codeprep import undefined_calls
from capmj.agents.lmp.session import LMPCall, LMPSession
from capmj.agents.report.checked import CheckedReporter
from capmj.agents.report.relations.checks import CHECKS, NAMES, SELECTORS, Failures, relation_env
from capmj.agents.report.relations.picks import ungrounded
from capmj.agents.report.scene import INVENTORY_KEYS, records, records_text, start_areas_of, state_from_api
from capmj.agents.report.verdict import Answer, Gate, Reading, Report, ask_for_verdict, gated, record_reading
from capmj.agents.sandbox import run_code
from capmj.errors import PlanError, UnknownCheckError, describe
from capmj.llm.provider import derived_seed
from capmj.sim.state import SceneState

__all__ = ["BLIND", "BLIND_GATE", "COVERAGE", "GATES", "HOLDS_AT_START", "IMPOSSIBLE", "LAYERED", "PROMPT", "Ran",
           "RelationsReporter", "uncovered"]

PROMPT = "reporter_relations"
"""The prompt file (``prompts/reporter_relations.py``) and the LMP name in transcripts."""

BLIND = "it calls none of the require_... checks, so it tests nothing: call the checks the goal asks for"
"""The problem the repair request states when the answer makes no ``require_*`` call."""

HOLDS_AT_START = ("every require_... call passes in the scene the robot started from, and no goal holds there: "
                  "require what the goal asks the robot to achieve (where the objects must be, stacks, layers ...)")
"""The problem the repair request states when the check finds nothing wrong with the start scene."""

LAYERED = ("require_stack of objects also required in layers of several is read as their place only: "
           "a structure with several blocks in a layer is require_layers")
"""The transcript note when a tower call is read as its place (:meth:`Failures.layered_towers`)."""

IMPOSSIBLE = "no arrangement of the objects could pass every require_... call, so it says \"not achieved\" of every scene"
"""The start of the problem the repair request states when the calls contradict each other."""

COPIED_RECORDS_HINT = ("# `objects` is already defined with the records above: do not write it out again. "
                       "Start with the first line of the check.\n")
"""Added to the repair request when the failed answer began by assigning ``objects``."""
_COPIES_RECORDS = re.compile(r"\A\s*(?:```[A-Za-z]*\s*)?objects\s*=")

REPAIR_TEMPERATURE = 0.7
"""Sampling temperature of the repair request (the first request uses the client's), with a seed
derived from the question: it can differ from the failed answer and still be repeated."""


# ------------------------------------------------------------------------------------------------
# what an answer's text leaves out (read from its tree, no task knowledge)
# ------------------------------------------------------------------------------------------------
PLACED = ("require_inside", "require_outside", "require_count")
"""Checks that say where objects must (not) be; ``require_stack(objs, place)`` does too."""

KEEP = "add one of {checks} to the calls the goal needs (keep the others)"
"""The advice of a repair request for a relation left out."""

COVERAGE: tuple[tuple[str, str, tuple[str, ...], str], ...] = (
    (r"\bstack", "a stack", ("require_stack", "require_layers"), KEEP),
    (r"\b(?:structure|layer)s?\b", "layers (a structure has several blocks in a layer; a tower is one column)",
     ("require_layers",), "write require_layers(objs, [n1, n2, ...]) with the number of blocks in each layer from the "
                          "table up, instead of require_stack"),
    (r"\b(?:circle|ring)s?\b", "a circle", ("require_circle",), KEEP),
    (r"\balternat", "alternating colours", ("require_alternating",), KEEP),
    (r"\b(?:in|on|into|onto)\s+(?:the|a|an|each|every)\s+(?:[a-z]+\s+){0,2}?(?:zone|bowl)s?\b",
     "where the objects must be (a zone or bowl)", PLACED, KEEP),
)
"""(goal pattern, what it asks for, the checks any one of which asks for it, the advice): a goal that
says "stack" asks for a stack or layers, "structure" or "layer" for layers (the prompt's own words
for ``require_layers``), "circle" or "ring" for a circle, "alternat..." for alternating colours,
"in/on/into the ... zone/bowl" for where the objects must be."""

def uncovered(code: Answer | str, goal: str) -> str | None:
    """Which relation the goal names and the check never asks for (a sentence for the repair request), or
    None (also when the code does not parse: the sandbox reports it)."""
    answer = code if isinstance(code, Answer) else Answer.read(code)
    if answer.tree is None:
        return None
    asked: set[str] = set()
    for name, call in answer.calls():
        asked.add(name)
        if name == "require_stack" and (len(call.args) > 1 or any(k.arg == "place" for k in call.keywords)):
            asked.add(PLACED[0])
    text = goal.lower()
    for pattern, relation, checks, advice in COVERAGE:
        found = re.search(pattern, text)
        if found and not asked & set(checks):
            return (f'the goal says "{found.group(0)}", but no call asks for {relation}: '
                    + advice.format(checks=", ".join(checks)))
    return None


# ------------------------------------------------------------------------------------------------
# the gates
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Ran:
    """An answer's check as run on the final scene: what :data:`GATES` read."""

    answer: Answer
    goal: str
    rows: list[dict[str, Any]]
    """The final scene's records."""
    asked: Failures
    """What its calls asked for, and what failed."""
    at_start: Callable[[], bool | None]
    """Its verdict on the start scene (run when asked; None: no start scene or the run failed)."""


def _impossible(ran: Ran) -> str | None:
    found = ran.asked.impossible()
    return f"{IMPOSSIBLE}: {found}" if found is not None else None


def _holds_at_start(ran: Ran) -> str | None:
    return HOLDS_AT_START + "".join(f"; {pick}" for pick in ran.asked.empty_picks[:1]) if ran.at_start() else None


BLIND_GATE: Gate[Answer] = Gate(
    "blind", "blind", "its check calls none of the require_... checks",
    lambda answer: None if any(name in CHECKS for name, _ in answer.calls()) or answer.tree is None else BLIND,
    keeps=False)
"""An answer that makes no ``require_*`` call tests nothing (tried before the run; an answer that does
not parse is the sandbox's to report)."""

GATES: tuple[Gate[Ran], ...] = (
    Gate("impossible_check", "impossible",
         "its check asks for relations no scene can satisfy together (relations prompt)", _impossible),
    Gate("ungrounded_literal", "ungrounded",
         "its check picks a block colour or a count the goal does not give (relations prompt)",
         lambda ran: ungrounded(ran.answer, ran.goal, ran.rows)),
    Gate("holds_at_start", None, "its check also says the goal holds in the scene the robot started from",
         _holds_at_start),
    Gate("misses_a_relation", "uncovered", "its check never asks for a relation the goal names (relations prompt)",
         lambda ran: uncovered(ran.answer, ran.goal)),
)
"""The gates of a check that ran, in the order they are tried: calls no scene can pass together
(:meth:`Failures.impossible`), a literal the goal does not give
(:func:`~capmj.agents.report.relations.picks.ungrounded`), every call
passing on the start scene (its run's transcript entries say it), a relation the goal names left
out (:func:`uncovered`)."""


def _vet(code: str) -> None:
    """UnknownCheckError for a call of a name the prompt does not define (never written by ``parse_function``)."""
    missing = [m[0] for m in undefined_calls(code, set(NAMES))]
    if missing:
        raise UnknownCheckError(f"{', '.join(missing)} is not defined; the checks are {', '.join(CHECKS)} "
                                f"and the selectors {', '.join(SELECTORS)}")


class RelationsReporter:
    """``--reporter-prompt relations``: the goal as calls of pre-bound relation checks (see the module docstring)."""

    mode = "text"
    prompt = "relations"
    gates: tuple[Gate[Any], ...] = (BLIND_GATE, *GATES)

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

    def judge(self, session: LMPSession, ctx: Any, goal: str) -> Report:
        said = " ".join(goal.split())
        question = f"# The objects of this scene.\n{records_text(self._records(session, ctx), INVENTORY_KEYS)}\n# goal: {said}"
        repair = (f"# Write the corrected complete check for the same goal: only calls of {', '.join(CHECKS)} "
                  f"on objects picked with {', '.join(SELECTORS)}. Do not set judge.\n# goal: {said}\n")
        warm = {"temperature": REPAIR_TEMPERATURE, "seed": derived_seed(f"capmj-records-repair/{question}")}
        return ask_for_verdict(
            session, self.mode, session.messages(session.prompt(PROMPT).render(question)),
            call=lambda source: session.next_call(PROMPT, goal),
            read=lambda call, answer, last: self._read(session, ctx, goal, call, answer, last),
            repair=lambda answer, problem: (f"# The checking code above failed: {problem}\n"
                                            f"{COPIED_RECORDS_HINT if _COPIES_RECORDS.match(answer.text) else ''}{repair}"),
            fallback=lambda errors: self._direct(session, ctx, goal, errors),
            sampling=lambda source: warm if source == "repair" else {})

    def _run(self, session: LMPSession, call: LMPCall, code: str, rows: list[dict[str, Any]],
             start: list[dict[str, Any]] | None, scene: str, label: str,
             layered: frozenset[frozenset[str]] = frozenset()) -> tuple[Reading, Failures | None]:
        """Run prepared ``code`` on one scene's records (``start``: the start scene's, for ``require_unmoved``;
        ``layered``: see :func:`relation_env`): the verdict is that no required relation failed, and what its
        calls asked for (None when it failed to run)."""
        env, failures = relation_env(rows, start, layered)
        try:
            run_code(code, env, budget=session.lmp_budget, filename=f"<{PROMPT} {session.attempt}.{call.n}{scene}>")
        except PlanError as exc:
            return record_reading(session, call, Reading(None, problem=describe(exc)), label), None
        return record_reading(session, call, Reading(not failures.items, failures.reason, failures.wrong), label), failures

    def _read(self, session: LMPSession, ctx: Any, goal: str, call: LMPCall, answer: Answer, last: bool) -> Reading:
        """The answer's check run on the final scene, through the gates (``last``: no repair follows)."""
        rows = self._records(session, ctx)
        start = records(self._start_state, self._start) if self._start_state is not None else None
        try:
            code = session.prepare_answer(call, answer.text, dict.fromkeys(NAMES), vet=_vet)  # drops benign imports only
        except PlanError as exc:
            return record_reading(session, call, Reading(None, problem=describe(exc)))
        blind = gated(session, call, (BLIND_GATE,), answer, Reading(None), last)
        if blind.problem is not None:
            return blind
        run, asked = self._run(session, call, code, rows, start, "", "result")
        layered = asked.layered_towers() if asked is not None else frozenset()
        if layered:
            session.record(call, "layered", LAYERED)
            run, asked = self._run(session, call, code, rows, start, "", "result", layered)
        if run.problem is not None or asked is None:
            return run

        def at_start() -> bool | None:
            return start is not None and self._run(session, call, code, start, start, " start", "start scene",
                                                   layered)[0].verdict

        return gated(session, call, GATES, Ran(answer, goal, rows, asked, at_start), run, last)

    def _direct(self, session: LMPSession, ctx: Any, goal: str, errors: tuple[str, ...]) -> Report:
        """The ``checked`` question after two failed checks: its verdict, as source ``direct``."""
        report = self._fallback.judge(session, ctx, goal)
        errors += tuple(f"direct {e}" for e in report.errors)
        source = "unknown" if report.verdict is None else "direct"
        return dataclasses.replace(report, source=source, errors=errors, error=errors[-1])

    def close(self) -> None:
        return None
