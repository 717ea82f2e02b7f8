"""A reporter's verdict: the :class:`Report`, the :class:`Answer` it is read from (parsed once, never
executed), the :class:`Gate` an answer must pass, and the one loop every reporter runs.

The loop (:func:`ask_for_verdict`): ask; read the answer (the reporter's own read: a literal
verdict parsed, or checking code run in the sandbox); pass it through the reporter's gates; on a
problem, one repair request in the same conversation quoting it; still a problem: the reporter's
fallback.  The :class:`Report` says which step gave the verdict (``source``):

1. ``code`` — the first answer;
2. ``repair`` — the answer to the one repair request;
3. ``direct`` — a fallback question without code or images (:func:`direct_verdict`:
   ``prompts/reporter_direct.txt``, the object poses and the goal; or a reporter's own);
4. ``unknown`` — none of these gave a bool.  What an unknown verdict does to the loop is the
   agent's ``on_unknown`` policy (:mod:`capmj.agents.llm_agent.agent`).
"""

from __future__ import annotations

import ast
import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from capmj.agents.lmp.codeprep import named_calls
from capmj.agents.lmp.session import LMPCall, LMPSession
from capmj.agents.prompt_files import prompts_dir
from capmj.agents.sandbox import extract_code
from capmj.errors import ConfigError, PlanError

__all__ = ["SOURCES", "Answer", "Gate", "Reading", "Report", "ask_for_verdict", "direct_verdict", "gated", "literal_reading",
           "names_of", "parse_verdict", "record_reading", "scene_listing"]

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
    """Why the reporter itself doubts this verdict: the key of the :class:`Gate` that kept it doubted
    (a low-confidence reason of :mod:`capmj.agents.report.confidence`)."""

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
# the answer, parsed once
# ------------------------------------------------------------------------------------------------
_NOT_LITERAL = object()


@dataclass(frozen=True)
class Answer:
    """One answer of the model, parsed once: its code, the syntax tree of the whole code (None when
    it has no code or does not parse) and the calls of a bare name in it, else the trees of its
    ``judge``/``reason``/``wrong`` lines parsed one by one (a broken block still yields its verdict
    lines)."""

    text: str
    code: str | None
    tree: ast.Module | None
    lines: tuple[ast.Module, ...] = ()
    named: tuple[tuple[str, ast.Call], ...] = ()
    """``(name, call)`` for every call of a bare name in the whole code, in :func:`ast.walk` order."""

    @classmethod
    def read(cls, text: str) -> Answer:
        try:
            code = extract_code(text)
        except PlanError:
            return cls(text, None, None)
        try:
            tree = ast.parse(code)
        except (SyntaxError, ValueError):
            lines = []
            for line in code.splitlines():
                stripped = line.strip()
                if stripped.startswith(("judge", "reason", "wrong")):
                    try:
                        lines.append(ast.parse(stripped))
                    except (SyntaxError, ValueError):
                        continue
            return cls(text, code, None, tuple(lines))
        return cls(text, code, tree, named=tuple(named_calls(tree)))

    @property
    def trees(self) -> tuple[ast.Module, ...]:
        return (self.tree,) if self.tree is not None else self.lines

    def calls(self, name: str | None = None) -> list[tuple[str, ast.Call]]:
        """The calls of a bare name in the whole code (only those of ``name`` when given)."""
        return [(n, call) for n, call in self.named if name in (None, n)]

    def literals(self, name: str) -> list[Any]:
        """The values of every ``name = <literal>`` assignment, nested ones too (a non-literal value
        is an opaque marker)."""
        return [v for tree in self.trees for v in _literals(tree, name)]

    def verdict(self) -> tuple[bool | None, str, str | None]:
        """``(judge, reason, problem)``: the verdict is known only when every literal ``judge``
        assignment agrees on one bool."""
        if self.code is None:
            return None, "", "no code in the answer"
        judges = self.literals("judge")
        reason = next((r for r in reversed(self.literals("reason")) if isinstance(r, str)), "")
        if not judges:
            return None, reason, "the answer sets no 'judge'"
        if any(not isinstance(j, bool) for j in judges):
            return None, reason, "'judge' is not assigned a literal True or False"
        if len(set(judges)) > 1:
            return None, reason, "the answer sets 'judge' to both True and False"
        return judges[0], reason, None

    def wrong(self) -> tuple[str, ...]:
        """The names of the last literal ``wrong = [...]`` (empty when there is none)."""
        for tree in reversed(self.trees):
            values = _literals(tree, "wrong")
            if values:
                return names_of(values[-1])
        return ()


def _literals(tree: ast.AST, name: str) -> list[Any]:
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


def parse_verdict(text: str) -> tuple[bool | None, str, str | None]:
    """``(judge, reason, problem)`` of a reporter answer (:meth:`Answer.verdict`); never executes anything."""
    return Answer.read(text).verdict()


def names_of(value: Any) -> tuple[str, ...]:
    """``value`` as a tuple of object names when it is a list/tuple/set of strings, else ()."""
    if isinstance(value, (list, tuple, set, frozenset)) and all(isinstance(v, str) for v in value):
        return tuple(dict.fromkeys(value))
    return ()


# ------------------------------------------------------------------------------------------------
# readings and gates
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Reading:
    """What one answer gave: a verdict, or the problem the repair request quotes."""

    verdict: bool | None
    reason: str = ""
    wrong: tuple[str, ...] = ()
    problem: str | None = None
    """None when the answer gave a bool verdict."""
    doubt: str | None = None
    """The key of the gate that kept this verdict doubted (becomes :attr:`Report.doubt`)."""


S = TypeVar("S")


@dataclass(frozen=True)
class Gate(Generic[S]):
    """A test an answer's reading must pass: a value with its key, its transcript label and its test.

    ``test(subject)`` gives the problem (a sentence the repair request quotes) or None.  A problem
    asks for the repair (``repairs``); after it, or at once when the gate never repairs, the verdict
    is kept low-confidence under ``key`` (``keeps``), or the answer fails and the fallback decides."""

    key: str
    label: str | None
    """The transcript entry its problem is recorded under (None: recorded by the test itself)."""
    why: str
    """Why a verdict it keeps is low-confidence (its line of the confidence reasons)."""
    test: Callable[[S], str | None]
    repairs: bool = True
    keeps: bool = True


def gated(session: LMPSession, call: LMPCall, gates: Sequence[Gate[S]], subject: S, reading: Reading,
          last: bool) -> Reading:
    """``reading`` through ``gates`` in order: the first that finds a problem decides (see :class:`Gate`)."""
    for gate in gates:
        problem = gate.test(subject)
        if problem is None:
            continue
        if gate.label is not None:
            session.record(call, gate.label, problem)
        if gate.keeps and (last or not gate.repairs):
            return dataclasses.replace(reading, doubt=gate.key)
        return Reading(None, problem=problem)
    return reading


def record_reading(session: LMPSession, call: LMPCall, reading: Reading, label: str = "result") -> Reading:
    """Record a verdict (under ``label``) or its problem (under ``error``, or ``<label> error``)."""
    if reading.problem is not None:
        session.record(call, "error" if label == "result" else f"{label} error", reading.problem)
    else:
        session.record(call, label, f"judge = {reading.verdict!r}\nreason = {reading.reason!r}\n"
                                    f"wrong = {list(reading.wrong)!r}")
    return reading


def literal_reading(session: LMPSession, call: LMPCall, answer: Answer) -> Reading:
    """The reading of an answer that states its verdict as literals (parsed, never run), recorded."""
    judge, reason, problem = answer.verdict()
    if problem is not None:
        return record_reading(session, call, Reading(None, reason, problem=problem))
    return record_reading(session, call, Reading(judge, reason, answer.wrong()))


# ------------------------------------------------------------------------------------------------
# the loop
# ------------------------------------------------------------------------------------------------
def ask_for_verdict(session: LMPSession, mode: str, messages: list[dict[str, Any]], *,
                    call: Callable[[str], LMPCall], read: Callable[[LMPCall, Answer, bool], Reading],
                    repair: Callable[[Answer, str], str], fallback: Callable[[tuple[str, ...]], Report],
                    sampling: Callable[[str], Mapping[str, Any]] = lambda source: {}) -> Report:
    """Ask → read → gates → one repair → fallback, the loop every reporter runs.

    ``call(source)`` names the request of each round (``code``, ``repair``), sent with
    ``sampling(source)``; ``read(call, answer, last)`` reads an answer and passes it through the
    reporter's gates (``last``: no repair follows); ``repair(answer, problem)`` is the repair
    request; ``fallback(errors)`` decides after two problems.  LLMError propagates: it ends the
    episode's attempts."""
    errors: tuple[str, ...] = ()
    for source in ("code", "repair"):
        asked = call(source)
        answer = Answer.read(session.ask(asked, messages, **sampling(source)))
        got = read(asked, answer, source == "repair")
        if got.problem is None:
            return Report(mode, got.verdict, got.reason, errors[-1] if errors else None, source, got.wrong, errors,
                          got.doubt)
        errors += (f"{source}: {got.problem}",)
        messages = messages + [{"role": "assistant", "content": answer.text},
                               {"role": "user", "content": repair(answer, got.problem)}]
    return fallback(errors)


def scene_listing(api: Mapping[str, Callable[..., Any]]) -> str:
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
    got = literal_reading(session, call, Answer.read(session.ask(call, session.messages(prompt))))
    if got.problem is not None:
        errors = errors + (f"direct: {got.problem}",)
        return Report(mode, None, got.reason, got.problem, "unknown", (), errors)
    return Report(mode, got.verdict, got.reason, errors[-1] if errors else None, "direct", got.wrong, errors)
