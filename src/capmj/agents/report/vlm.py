"""The ``vlm`` reporter: a vision-language model gets the initial and the final RGB image of the
FRONT camera plus the final depth as a *visible* colour map (the original converted metric depth
to 8-bit integers, i.e. an almost black image) and answers with a code block setting ``judge``.
The verdict is read by parsing that code and literal-evaluating the assignment
(:class:`capmj.agents.report.verdict.Answer`; the original searched the answer for the substring
"True", so "not True" counted as success), in the reporters' one loop
(:func:`~capmj.agents.report.verdict.ask_for_verdict`).  No renderer, or no verdict after one
repair: the direct verdict takes over.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from capmj.agents.base import JUDGE_SETTLE_STEPS
from capmj.agents.lmp.session import LMPSession
from capmj.agents.prompt_files import load_system_prompt, prompts_dir
from capmj.agents.report.verdict import Gate, Report, ask_for_verdict, direct_verdict, literal_reading
from capmj.errors import CapmjError, ConfigError, describe


class VLMReporter:
    """Front-camera images (initial RGB, final RGB, final depth colour map) to a VLM."""

    mode = "vlm"
    camera = "front"
    gates: tuple[Gate[Any], ...] = ()

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
        return ask_for_verdict(
            session, self.mode, messages,
            call=lambda source: call if source == "code" else session.next_call("vlm_reporter", goal),
            read=lambda asked, answer, last: literal_reading(session, asked, answer),
            repair=lambda answer, problem: (
                f"Your answer gave no verdict: {problem}. Answer only with one ```python block that sets judge = True "
                "or False and reason = a short explanation."),
            fallback=lambda errors: direct_verdict(session, goal, self.mode, errors))

    def close(self) -> None:
        if self._rig is not None:
            try:
                self._rig.close()
            finally:
                self._rig = None

