"""Reporters: after a plan ran, judge whether the goal is achieved (and explain why not).

Two modes, as in CapRavens:

* **text** — the ``parse_completion`` LMP writes checking code over the live object poses
  (``get_obj_pos_dict()``...) that sets ``judge`` (bool) and ``reason``; the code runs in the
  sandbox with the read-only API.
* **vlm** — a vision-language model gets the initial and the final RGB image of the FRONT camera
  plus the final depth as a *visible* colour map (the original converted metric depth to 8-bit
  integers, i.e. an almost black image) and answers with a code block setting ``judge``.  The
  verdict is read by parsing that code and literal-evaluating the assignment (the original
  searched the answer for the substring "True", so "not True" counted as success).

A verdict is ``True``, ``False`` or ``None`` (unknown: unparseable answer, failing checking code,
no renderer); only ``False`` triggers a re-plan.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from typing import Any

import numpy as np

from capmj.agents.lmp import LMPSession, load_system_prompt, prompts_dir
from capmj.agents.sandbox import extract_code
from capmj.errors import CapmjError, ConfigError, PlanError

__all__ = ["REPORTERS", "Report", "TextReporter", "VLMReporter", "make_reporter", "parse_verdict"]

REPORTERS = ("none", "text", "vlm")


@dataclass(frozen=True)
class Report:
    """A reporter's judgement of the final scene."""

    mode: str
    verdict: bool | None
    reason: str = ""
    error: str | None = None

    def text(self) -> str:
        word = {True: "ACHIEVED", False: "NOT ACHIEVED", None: "UNKNOWN"}[self.verdict]
        out = f"reporter ({self.mode}): goal {word}"
        if self.reason:
            out += f"; {self.reason}"
        if self.error:
            out += f" [{self.error}]"
        return out


# ------------------------------------------------------------------------------------------------
# verdict parsing
# ------------------------------------------------------------------------------------------------
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


_NOT_LITERAL = object()


def parse_verdict(text: str) -> tuple[bool | None, str, str | None]:
    """``(judge, reason, problem)`` from a reporter answer.

    The code block(s) of the answer are parsed with :mod:`ast` and every top-level or nested
    ``judge = <literal>`` assignment is literal-evaluated; the verdict is known only when all of
    them agree on one bool.  When the block does not parse as a whole, each line that assigns
    ``judge``/``reason`` is parsed on its own.  Never executes anything.
    """
    try:
        code = extract_code(text)
    except PlanError:
        return None, "", "no code in the answer"
    trees: list[ast.AST] = []
    try:
        trees.append(ast.parse(code))
    except (SyntaxError, ValueError):
        for line in code.splitlines():
            stripped = line.strip()
            if stripped.startswith(("judge", "reason")):
                try:
                    trees.append(ast.parse(stripped))
                except (SyntaxError, ValueError):
                    continue
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


# ------------------------------------------------------------------------------------------------
# text reporter
# ------------------------------------------------------------------------------------------------
class TextReporter:
    """``parse_completion`` over the live scene."""

    mode = "text"

    def start(self, ctx: Any) -> None:  # nothing to capture before acting
        return None

    def judge(self, session: LMPSession, ctx: Any, goal: str) -> Report:
        judge, reason = session.parse_completion(goal)
        calls = [c for c in session.transcript if c.lmp == "parse_completion" and c.attempt == session.attempt]
        error = calls[-1].error if calls and calls[-1].error else None
        return Report(self.mode, judge, reason, error)

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
        except Exception as exc:  # noqa: BLE001 - no renderer: the verdict becomes unknown
            self._render_error = f"{type(exc).__name__}: {exc}"
        else:
            ctx.recorder.image("llm/vlm/initial_rgb", self._initial)

    def images(self, ctx: Any) -> tuple[bytes, bytes, bytes, np.ndarray, np.ndarray]:
        """PNG bytes of (initial RGB, final RGB, final depth colour map) and the raw final images."""
        from capmj.sim.cameras import depth_to_visible, to_png

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
        from pathlib import Path

        from capmj.llm import image_part, text_part

        call = session.next_call("vlm_reporter", goal)
        try:
            ctx.world.settle(max_steps=1000)
            png_initial, png_final, png_depth, rgb, depth = self.images(ctx)
        except (CapmjError, RuntimeError, OSError) as exc:
            error = f"no images: {type(exc).__name__}: {exc}"
            session.record(call, "error", error)
            return Report(self.mode, None, "", error)
        rec = session.recorder
        base = f"llm/attempt{session.attempt}/vlm_reporter/{call.n}"
        rec.image(f"{base}/final_rgb", rgb)
        rec.depth(f"{base}/final_depth", depth.astype(np.float32))
        rec.image(f"{base}/final_depth_colormap", self.last_visible_depth)
        folder = Path(self.directory) if self.directory is not None else prompts_dir()
        objects = [o.name for o in ctx.world.objects]
        content = [
            text_part(self.prompt_text(goal, objects)),
            text_part("Image 1 (before):"), image_part(png_initial),
            text_part("Image 2 (after):"), image_part(png_final),
            text_part("Image 3 (depth after, colour map):"), image_part(png_depth),
        ]
        messages = [{"role": "system", "content": load_system_prompt(folder)},
                    {"role": "user", "content": content}]
        text = session.ask(call, messages)  # LLMError propagates: it ends the episode's attempts
        judge, reason, problem = parse_verdict(text)
        if problem:
            session.record(call, "error", problem)
        session.record(call, "result", f"judge = {judge!r}\nreason = {reason!r}")
        return Report(self.mode, judge, reason, problem)

    def close(self) -> None:
        if self._rig is not None:
            try:
                self._rig.close()
            finally:
                self._rig = None


def make_reporter(mode: str, prompt_directory: Any = None) -> TextReporter | VLMReporter | None:
    if mode == "none":
        return None
    if mode == "text":
        return TextReporter()
    if mode == "vlm":
        return VLMReporter(prompt_directory)
    raise ConfigError(f"unknown reporter {mode!r}; valid reporters: {', '.join(REPORTERS)}")
