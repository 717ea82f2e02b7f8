"""A reporter's verdict: the :class:`Report`, how it is read from an answer (parsed with
:mod:`ast`, never executed), and the two ways of asking for one that every reporter shares.

Every reporter tries hard to reach a verdict; the :class:`Report` says which step gave it
(``source``):

1. ``code`` — the first answer (text: its checking code ran and set a bool ``judge``; vlm: its
   code block assigns a literal bool);
2. ``repair`` — one more request in the same conversation, with the error (and the failing line);
3. ``direct`` — a structured question without code or images (``prompts/reporter_direct.txt``):
   the object poses and the goal, answered as ``judge = True/False`` + ``reason`` (+ ``wrong``),
   parsed with :mod:`ast`, never executed (:func:`direct_verdict`);
4. ``unknown`` — none of these gave a bool.  What an unknown verdict does to the loop is the
   agent's ``on_unknown`` policy (:mod:`capmj.agents.llm_agent.agent`).

The reporters themselves are :mod:`capmj.agents.report.text` (text), :mod:`capmj.agents.report.vlm`
and :mod:`capmj.agents.report.checked`.
"""

from __future__ import annotations

import ast
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from capmj.agents.lmp.session import LMPCall, LMPSession
from capmj.agents.prompt_files import prompts_dir
from capmj.agents.sandbox import extract_code, run_code
from capmj.errors import ConfigError, PlanError, describe

__all__ = ["SOURCES", "CheckRun", "Report", "ask_verdict", "check", "direct_verdict", "parse_verdict", "parse_wrong",
           "rerun_check", "scene_listing"]

SOURCES = ("code", "repair", "direct", "unknown")
"""Where a verdict came from (see the module docstring), in the order they are tried."""


@dataclass(frozen=True)
class Report:
    """A reporter's judgement of the final scene."""

    mode: str
    verdict: bool | None
    reason: str = ""
    error: str | None = None
    """The last problem met on the way (None when the first answer gave the verdict)."""
    source: str = "unknown"
    wrong: tuple[str, ...] = ()
    """Objects whose state the reporter says is wrong (when it named them)."""
    errors: tuple[str, ...] = ()
    """Every problem met on the way, in order (``"code: ..."``, ``"repair: ..."``, ...)."""
    doubt: str | None = None
    """Why the reporter itself doubts this verdict: a key of :data:`capmj.agents.report.confidence.LOW_CONFIDENCE`
    (``copies_example``: the reason is the prompt's own example word for word; ``holds_at_start``: the
    check also says "achieved" of the scene the robot started from)."""

    def text(self) -> str:
        word = {True: "ACHIEVED", False: "NOT ACHIEVED", None: "UNKNOWN"}[self.verdict]
        out = f"reporter ({self.mode}): goal {word}"
        if self.reason:
            out += f"; {self.reason}"
        if self.wrong:
            out += f"\nobjects whose state is wrong: {list(self.wrong)}"
        if self.error and self.verdict is None:  # how a known verdict was reached is in ``errors``
            out += f" [{self.error}]"
        return out


# ------------------------------------------------------------------------------------------------
# verdict parsing
# ------------------------------------------------------------------------------------------------
_NOT_LITERAL = object()


def _literal_assignments(tree: ast.AST, name: str) -> list[Any]:
    values: list[Any] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign):
            targets, value = node.targets, node.value
        elif isinstance(node, ast.AnnAssign) and node.value is not None:
            targets, value = [node.target], node.value
        else:
            continue
        if any(isinstance(t, ast.Name) and t.id == name for t in targets):
            try:
                values.append(ast.literal_eval(value))
            except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
                values.append(_NOT_LITERAL)
    return values


def _answer_trees(text: str) -> list[ast.AST] | None:
    """Syntax trees of an answer's code: the whole block, else each ``judge``/``reason``/``wrong``
    line on its own (a broken block still yields its verdict lines); None without code."""
    try:
        code = extract_code(text)
    except PlanError:
        return None
    try:
        return [ast.parse(code)]
    except (SyntaxError, ValueError):
        trees: list[ast.AST] = []
        for line in code.splitlines():
            stripped = line.strip()
            if stripped.startswith(("judge", "reason", "wrong")):
                try:
                    trees.append(ast.parse(stripped))
                except (SyntaxError, ValueError):
                    continue
        return trees


def parse_verdict(text: str) -> tuple[bool | None, str, str | None]:
    """``(judge, reason, problem)`` from a reporter answer.

    The code block(s) of the answer are parsed with :mod:`ast` and every top-level or nested
    ``judge = <literal>`` assignment is literal-evaluated; the verdict is known only when all of
    them agree on one bool.  When the block does not parse as a whole, each line that assigns
    ``judge``/``reason`` is parsed on its own.  Never executes anything.
    """
    trees = _answer_trees(text)
    if trees is None:
        return None, "", "no code in the answer"
    judges = [v for t in trees for v in _literal_assignments(t, "judge")]
    reasons = [v for t in trees for v in _literal_assignments(t, "reason")]
    reason = next((r for r in reversed(reasons) if isinstance(r, str)), "")
    if not judges:
        return None, reason, "the answer sets no 'judge'"
    if any(not isinstance(j, bool) for j in judges):
        return None, reason, "'judge' is not assigned a literal True or False"
    if len(set(judges)) > 1:
        return None, reason, "the answer sets 'judge' to both True and False"
    return judges[0], reason, None


def parse_wrong(text: str) -> tuple[str, ...]:
    """The names of a literal ``wrong = [...]`` list in an answer (empty when there is none)."""
    for tree in reversed(_answer_trees(text) or []):
        for value in reversed(_literal_assignments(tree, "wrong")):
            return names_of(value)
    return ()


def names_of(value: Any) -> tuple[str, ...]:
    """``value`` as a tuple of object names when it is a list/tuple/set of strings, else ()."""
    if isinstance(value, (list, tuple, set, frozenset)) and all(isinstance(v, str) for v in value):
        return tuple(dict.fromkeys(value))
    return ()


def scene_listing(api: Any) -> str:
    """One line per object: centre [x, y, z] (m) and tilt (degrees from upright)."""
    lines = []
    for name, (pos, rpy) in api["get_obj_pos_dict"]().items():
        quarter = math.pi / 2
        tilt = max(min(abs(a) % quarter, quarter - abs(a) % quarter) for a in rpy[:2])
        lines.append(f"- {name}: centre [{pos[0]:.3f}, {pos[1]:.3f}, {pos[2]:.3f}], "
                     f"tilt {math.degrees(tilt):.0f} deg")
    return "\n".join(lines)


def direct_verdict(session: LMPSession, goal: str, mode: str, errors: tuple[str, ...] = ()) -> Report:
    """Ask for ``judge``/``reason``/``wrong`` from the object poses alone; parse, never execute."""
    folder = session.directory if session.directory is not None else prompts_dir()
    try:
        template = (folder / "reporter_direct.txt").read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"direct reporter prompt {folder / 'reporter_direct.txt'} not found") from None
    call = session.next_call("reporter_direct", goal)
    prompt = template.replace("<<STATE>>", scene_listing(session.api)).replace("<<GOAL>>", " ".join(goal.split()))
    text = session.ask(call, session.messages(prompt))
    judge, reason, problem = parse_verdict(text)
    if problem is not None:
        session.record(call, "error", problem)
        errors = errors + (f"direct: {problem}",)
        return Report(mode, None, reason, problem, "unknown", (), errors)
    wrong = parse_wrong(text)
    session.record(call, "result", f"judge = {judge!r}\nreason = {reason!r}\nwrong = {list(wrong)!r}")
    return Report(mode, judge, reason, errors[-1] if errors else None, "direct", wrong, errors)


def ask_verdict(session: LMPSession, mode: str, call_for: Callable[[str], LMPCall], messages: list[dict[str, Any]],
                repair_hint: str) -> tuple[Report | None, tuple[str, ...]]:
    """Ask for a verdict answer (``judge``, ``reason``, ``wrong``), with one repair round when it
    gives none: ``(report, errors)``, ``report`` None when both rounds failed.  Shared by the
    answer-only reporters (VLM, checked); ``call_for(source)`` names the call of each round.
    LLMError propagates: it ends the episode's attempts."""
    errors: tuple[str, ...] = ()
    for source in ("code", "repair"):
        call = call_for(source)
        text = session.ask(call, messages)
        judge, reason, problem = parse_verdict(text)
        if problem is None:
            wrong = parse_wrong(text)
            session.record(call, "result", f"judge = {judge!r}\nreason = {reason!r}\nwrong = {list(wrong)!r}")
            return Report(mode, judge, reason, errors[-1] if errors else None, source, wrong, errors), errors
        session.record(call, "error", problem)
        errors += (f"{source}: {problem}",)
        messages = messages + [{"role": "assistant", "content": text},
                               {"role": "user", "content": f"Your answer gave no verdict: {problem}. {repair_hint}"}]
    return None, errors


# ------------------------------------------------------------------------------------------------
# verdicts computed by checking code (the text reporters that let the model write code)
# ------------------------------------------------------------------------------------------------
def _failing_line(exc: PlanError, code: str) -> str:
    """A new line quoting ``line N: <source>`` of ``code`` when the error has a line, else ``""``."""
    lines = code.splitlines()
    if exc.line is None or not 1 <= exc.line <= len(lines):
        return ""
    return f"\n    line {exc.line}: {lines[exc.line - 1].strip()}"


@dataclass(frozen=True)
class CheckRun:
    """One run of model-written checking code: its verdict, or the problem that stopped it."""

    verdict: bool | None
    reason: str = ""
    wrong: tuple[str, ...] = ()
    problem: str | None = None
    """None when the code set a bool ``judge``."""
    code: str = ""
    """The code as run (after :meth:`LMPSession.prepare`): what :func:`rerun_check` runs again."""
    doubt: str | None = None
    """Why the reporter doubts this run's verdict (becomes :attr:`Report.doubt`)."""


def check(session: LMPSession, call: LMPCall, text: str, env: dict[str, Any], filename: str) -> CheckRun:
    """The :class:`CheckRun` of the checking code in ``text``, run in the sandbox with ``env``."""
    code = ""
    try:
        code = extract_code(text)
        code = session.prepare(code, env, parent=call)
        session.record(call, "code", code)
    except PlanError as exc:
        problem = f"{describe(exc)}{_failing_line(exc, code)}"
        session.record(call, "error", problem)
        return CheckRun(None, problem=problem, code=code)
    return rerun_check(session, call, code, env, filename, "result")


def rerun_check(session: LMPSession, call: LMPCall, code: str, env: dict[str, Any], filename: str,
                label: str) -> CheckRun:
    """Run prepared checking ``code`` with ``env``; the outcome is recorded under ``label``
    (``result``; a problem under ``error``, or ``<label> error`` for another label)."""
    failed = "error" if label == "result" else f"{label} error"
    try:
        ns = run_code(code, env, budget=session.lmp_budget, filename=filename)
    except PlanError as exc:
        problem = f"{describe(exc)}{_failing_line(exc, code)}"
        session.record(call, failed, problem)
        return CheckRun(None, problem=problem, code=code)
    judge, reason = ns.get("judge"), ns.get("reason")
    reason = reason if isinstance(reason, str) else ""
    if not isinstance(judge, (bool, np.bool_)):
        problem = ("the code did not set 'judge'" if "judge" not in ns
                   else f"'judge' is {type(judge).__name__} {str(judge)[:80]!r}, not True or False")
        session.record(call, failed, problem)
        return CheckRun(None, reason, problem=problem, code=code)
    wrong = names_of(ns.get("wrong"))
    session.record(call, label, f"judge = {bool(judge)!r}\nreason = {reason!r}\nwrong = {list(wrong)!r}")
    return CheckRun(bool(judge), reason, wrong, None, code)
