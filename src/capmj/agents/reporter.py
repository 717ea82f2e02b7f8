"""Reporters: after a plan ran, judge whether the goal is achieved (and explain why not).

Two modes, as in CapRavens:

* **text** — the ``parse_completion`` LMP writes checking code over the settled scene that sets
  ``judge`` (bool), ``reason`` and optionally ``wrong`` (names of the objects whose state is
  wrong); the code runs in the sandbox with the read-only API plus the pre-bound names of
  :mod:`capmj.agents.reporter_env` (``poses``, ``sizes``, ``goal_objects``, ``in_zone`` ...), so a
  completion that drops its first line still runs.
* **vlm** — a vision-language model gets the initial and the final RGB image of the FRONT camera
  plus the final depth as a *visible* colour map (the original converted metric depth to 8-bit
  integers, i.e. an almost black image) and answers with a code block setting ``judge``.  The
  verdict is read by parsing that code and literal-evaluating the assignment (the original
  searched the answer for the substring "True", so "not True" counted as success).

Both modes try hard to reach a verdict; the :class:`Report` says which step gave it
(``source``):

1. ``code`` — the first answer (text: its checking code ran and set a bool ``judge``; vlm: its
   code block assigns a literal bool);
2. ``repair`` — one more request in the same conversation, with the error (and the failing line);
3. ``direct`` — a structured question without code or images (``prompts/reporter_direct.txt``):
   the object poses and the goal, answered as ``judge = True/False`` + ``reason`` (+ ``wrong``),
   parsed with :mod:`ast`, never executed;
4. ``unknown`` — none of these gave a bool.  What an unknown verdict does to the loop is the
   agent's ``on_unknown`` policy (:mod:`capmj.agents.llm_agent`).
"""

from __future__ import annotations

import ast
import math
from dataclasses import dataclass
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from capmj.agents.base import JUDGE_SETTLE_STEPS
from capmj.agents.lmp import LMPCall, LMPSession, load_system_prompt, prompts_dir
from capmj.agents.reporter_env import PREBOUND, reporter_env
from capmj.agents.sandbox import extract_code, run_code
from capmj.errors import CapmjError, ConfigError, PlanError, describe


__all__ = ["REPORTERS", "REPORTER_PROMPTS", "SOURCES", "Report", "TextReporter", "VLMReporter", "ask_verdict", "direct_verdict",
           "make_reporter", "parse_verdict", "parse_wrong"]

REPORTERS = ("none", "text", "vlm")
REPORTER_PROMPTS = ("thesis", "checked")
"""``--reporter-prompt``: :class:`TextReporter`, or :class:`~capmj.agents.reporter_checked.CheckedReporter`."""
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
            return _names(value)
    return ()


def _names(value: Any) -> tuple[str, ...]:
    """``value`` as a tuple of object names when it is a list/tuple/set of strings, else ()."""
    if isinstance(value, (list, tuple, set, frozenset)) and all(isinstance(v, str) for v in value):
        return tuple(dict.fromkeys(value))
    return ()


def _is_bool(value: Any) -> bool:
    return isinstance(value, (bool, np.bool_))


def _failing_line(exc: PlanError, code: str) -> str:
    """A new line quoting ``line N: <source>`` of ``code`` when the error has a line, else ``""``."""
    lines = code.splitlines()
    if exc.line is None or not 1 <= exc.line <= len(lines):
        return ""
    return f"\n    line {exc.line}: {lines[exc.line - 1].strip()}"


# ------------------------------------------------------------------------------------------------
# the direct structured verdict (fallback of both modes)
# ------------------------------------------------------------------------------------------------
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
            verdict, reason, wrong, problem = self._run(session, call, text, ctx, goal, question)
            if problem is None:
                return Report(self.mode, verdict, reason, errors[-1] if errors else None, source, wrong, errors)
            errors += (f"{source}: {problem}",)
            messages = messages + [{"role": "assistant", "content": text},
                                   {"role": "user", "content": _repair_request(problem, question)}]
        return direct_verdict(session, goal, self.mode, errors)

    @staticmethod
    def _run(session: LMPSession, call: LMPCall, text: str, ctx: Any, goal: str, question: str
             ) -> tuple[bool | None, str, tuple[str, ...], str | None]:
        """(verdict, reason, wrong, problem) of one answer's checking code."""
        env = session.helper_env(question)
        env.update(reporter_env(session.api, ctx.world.objects, goal))  # fresh: code may mutate it
        code = ""
        try:
            code = extract_code(text)
            code = session.prepare(code, env, parent=call)
            session.record(call, "code", code)
            ns = run_code(code, env, budget=session.lmp_budget,
                          filename=f"<parse_completion {session.attempt}.{call.n}>")
        except PlanError as exc:
            problem = f"{describe(exc)}{_failing_line(exc, code)}"
            session.record(call, "error", problem)
            return None, "", (), problem
        judge, reason = ns.get("judge"), ns.get("reason")
        reason = reason if isinstance(reason, str) else ""
        if not _is_bool(judge):
            problem = ("the code did not set 'judge'" if "judge" not in ns
                       else f"'judge' is {type(judge).__name__} {str(judge)[:80]!r}, not True or False")
            session.record(call, "error", problem)
            return None, reason, (), problem
        wrong = _names(ns.get("wrong"))
        session.record(call, "result", f"judge = {bool(judge)!r}\nreason = {reason!r}\nwrong = {list(wrong)!r}")
        return bool(judge), reason, wrong, None

    def close(self) -> None:
        return None


# ------------------------------------------------------------------------------------------------
# VLM reporter
# ------------------------------------------------------------------------------------------------
class VLMReporter:
    """Front-camera images (initial RGB, final RGB, final depth colour map) to a VLM."""

    mode = "vlm"
    camera = "front"

    def __init__(self, prompt_directory: Any = None) -> None:
        self.directory = prompt_directory
        self._rig: Any = None
        self._initial: np.ndarray | None = None
        self._render_error: str | None = None
        self.last_visible_depth: np.ndarray | None = None

    # -- images ----------------------------------------------------------------------------
    def _render(self, ctx: Any) -> tuple[np.ndarray, np.ndarray]:
        from capmj.sim.cameras import CameraRig

        if self._rig is None:
            self._rig = CameraRig(ctx.world)
        frame = self._rig.render(self.camera)
        return np.asarray(frame.rgb), np.asarray(frame.depth)

    def start(self, ctx: Any) -> None:
        """Capture the initial front RGB image (before the first attempt acts)."""
        try:
            self._initial, _ = self._render(ctx)
        except Exception as exc:  # noqa: BLE001 - no renderer: the direct verdict takes over
            self._render_error = describe(exc)
        else:
            ctx.recorder.image("llm/vlm/initial_rgb", self._initial)

    def images(self, ctx: Any) -> tuple[bytes, bytes, bytes, np.ndarray, np.ndarray]:
        """PNG bytes of (initial RGB, final RGB, final depth colour map) and the raw final images."""
        from capmj.sim.image_colour import depth_to_visible, to_png

        if self._initial is None:
            raise ConfigError(f"no initial image: {self._render_error or 'start() was not called'}")
        rgb, depth = self._render(ctx)
        self.last_visible_depth = visible = depth_to_visible(depth)
        return to_png(self._initial), to_png(rgb), to_png(visible), rgb, depth

    def prompt_text(self, goal: str, objects: list[str]) -> str:
        folder = self.directory if self.directory is not None else prompts_dir()
        try:
            template = (folder / "vlm_reporter.txt").read_text(encoding="utf-8")
        except FileNotFoundError:
            raise ConfigError(f"VLM reporter prompt {folder / 'vlm_reporter.txt'} not found") from None
        listing = "\n".join(f"- {name}" for name in objects)
        return template.replace("<<OBJECTS>>", listing).replace("<<GOAL>>", goal.strip())

    # -- judging ---------------------------------------------------------------------------
    def judge(self, session: LMPSession, ctx: Any, goal: str) -> Report:
        from capmj.llm import image_part, text_part

        call = session.next_call("vlm_reporter", goal)
        try:
            ctx.world.settle(max_steps=JUDGE_SETTLE_STEPS)
            png_initial, png_final, png_depth, rgb, depth = self.images(ctx)
        except (CapmjError, RuntimeError, OSError) as exc:
            error = f"no images: {describe(exc)}"
            session.record(call, "error", error)
            return direct_verdict(session, goal, self.mode, (f"code: {error}",))
        rec = session.recorder
        base = f"llm/attempt{session.attempt}/vlm_reporter/{call.n}"
        rec.image(f"{base}/final_rgb", rgb)
        rec.depth(f"{base}/final_depth", depth.astype(np.float32))
        assert self.last_visible_depth is not None  # self.images() has just set it
        rec.image(f"{base}/final_depth_colormap", self.last_visible_depth)
        folder = Path(self.directory) if self.directory is not None else prompts_dir()
        objects = [o.name for o in ctx.world.objects]
        content = [
            text_part(self.prompt_text(goal, objects)),
            text_part("Image 1 (before):"), image_part(png_initial),
            text_part("Image 2 (after):"), image_part(png_final),
            text_part("Image 3 (depth after, colour map):"), image_part(png_depth),
        ]
        messages: list[dict[str, Any]] = [{"role": "system", "content": load_system_prompt(folder)},
                                          {"role": "user", "content": content}]
        first = call
        report, errors = ask_verdict(
            session, self.mode, lambda source: first if source == "code" else session.next_call("vlm_reporter", goal),
            messages, "Answer only with one ```python block that sets judge = True or False and reason = a short "
            "explanation.")
        return report if report is not None else direct_verdict(session, goal, self.mode, errors)

    def close(self) -> None:
        if self._rig is not None:
            try:
                self._rig.close()
            finally:
                self._rig = None


def make_reporter(mode: str, prompt_directory: Any = None, prompt: str = "thesis") -> Any:
    """The reporter of ``mode`` (None for ``none``); ``prompt`` selects the text reporter's prompt."""
    if prompt not in REPORTER_PROMPTS or (prompt != "thesis" and mode == "vlm"):
        raise ConfigError(f"reporter prompt {prompt!r}: valid: {', '.join(REPORTER_PROMPTS)} (not thesis: text only)")
    if mode == "none":
        return None
    if mode == "text" and prompt == "checked":
        from capmj.agents.reporter_checked import CheckedReporter

        return CheckedReporter(prompt_directory)
    if mode == "text":
        return TextReporter()
    if mode == "vlm":
        return VLMReporter(prompt_directory)
    raise ConfigError(f"unknown reporter {mode!r}; valid reporters: {', '.join(REPORTERS)}")


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
