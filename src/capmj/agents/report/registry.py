"""The reporter plugin axis: the :class:`Reporter` protocol, and reporters built by name.

A reporter judges, after a plan ran, whether the goal is achieved.  The closed loop
(:class:`~capmj.agents.llm_agent.agent.LLMAgent`) and the judge (:mod:`capmj.judge.evaluate`) call it
the same way: :meth:`Reporter.start` before the first attempt acts, :meth:`Reporter.judge` on each
settled scene to be judged, :meth:`Reporter.close` at the end.  The reporters are named once, in
:data:`capmj.agents.choices.REPORTER_TABLE` (``--reporter`` → ``--reporter-prompt`` →
``"module:attribute"`` of a class taking the prompt directory); :func:`make_reporter` reads that
table and imports a reporter's module only when it is asked for.
"""

from __future__ import annotations

import functools
import importlib
from pathlib import Path
from typing import Any, Protocol, cast

from capmj.agents.base import EpisodeContext
from capmj.agents.choices import REPORTER_PROMPTS, REPORTER_TABLE, REPORTERS
from capmj.agents.lmp.session import LMPSession
from capmj.agents.report.verdict import Gate, Report
from capmj.errors import ConfigError

__all__ = ["Reporter", "ReporterClass", "load_reporter", "make_reporter"]


class Reporter(Protocol):
    """What the closed loop and the judge call on a reporter."""

    mode: str
    """``text`` or ``vlm``: the :attr:`Report.mode` of its reports."""
    gates: tuple[Gate[Any], ...]
    """The gates its answers pass (:class:`~capmj.agents.report.verdict.Gate`; empty for none): the
    low-confidence reasons are derived from them."""

    def start(self, ctx: EpisodeContext) -> None:
        """Before the first attempt acts: capture what the judging needs of the initial scene."""

    def judge(self, session: LMPSession, ctx: EpisodeContext, goal: str) -> Report:
        """The verdict on the scene as it is now (settled by the caller); its LMP calls go through
        ``session``."""

    def close(self) -> None:
        """At the end of the episode: release what :meth:`start` took (a renderer)."""


class ReporterClass(Protocol):
    """What :data:`~capmj.agents.choices.REPORTER_TABLE` names: a reporter class, built with the
    prompt directory (``None``: the packaged prompts)."""

    gates: tuple[Gate[Any], ...]

    def __call__(self, prompt_directory: Path | str | None = None) -> Reporter: ...


def load_reporter(target: str) -> ReporterClass:
    """The class a ``"module:attribute"`` target of the table names (its module imported now)."""
    module, _, attr = target.partition(":")
    return cast(ReporterClass, functools.reduce(getattr, attr.split("."), importlib.import_module(module)))


def make_reporter(mode: str, prompt_directory: Path | str | None = None, prompt: str = "thesis") -> Reporter | None:
    """The reporter of ``mode`` (None for ``none``); ``prompt`` selects the text reporter's prompt."""
    prompts = REPORTER_TABLE.get(mode)
    if prompt not in REPORTER_PROMPTS or (prompts and prompt not in prompts):
        raise ConfigError(f"reporter prompt {prompt!r}: valid: {', '.join(REPORTER_PROMPTS)} (not thesis: text only)")
    if prompts is None:
        raise ConfigError(f"unknown reporter {mode!r}; valid reporters: {', '.join(REPORTERS)}")
    if not prompts:
        return None
    return load_reporter(prompts[prompt].target)(prompt_directory)
