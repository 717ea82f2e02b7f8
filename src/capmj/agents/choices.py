"""The names the LLM agent's loop options take, in one import-light module.

The command line (:mod:`capmj.bench.options`, whose ``choices`` and help name the valid values), the
agent's option record (:mod:`capmj.agents.llm_agent.options`) and the modules that give the names their
meaning (:mod:`capmj.agents.report.registry`, :mod:`capmj.agents.llm_agent.loop_policy`) all read them.  They
live here, importing nothing of capmj, so the bench's parser does not import the reporters (and
litellm's neighbours) to build its help, and a new reporter is added in one place: a line of
:data:`REPORTER_TABLE`.
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["FEEDBACKS", "INTERACTIONS", "LOOP_POLICIES", "ON_UNKNOWN", "POLICIES", "REPORTERS", "REPORTER_PROMPTS", "REPORTER_TABLE", "ReporterEntry",
           "reporter_prompt_help"]


class ReporterEntry(NamedTuple):
    """One reporter of :data:`REPORTER_TABLE`."""

    target: str
    """``module:attribute`` of its class, called with the prompt directory (imported when asked for)."""
    about: str
    """What it is, for the help of ``--reporter-prompt``."""


REPORTER_TABLE: dict[str, dict[str, ReporterEntry]] = {
    "none": {},
    "text": {
        "thesis": ReporterEntry("capmj.agents.report.text:TextReporter", "default: checking code"),
        "checked": ReporterEntry("capmj.agents.report.checked:CheckedReporter", "capmj binds the scene facts as text"),
        "relations": ReporterEntry("capmj.agents.report.relations.reporter:RelationsReporter",
                                   "the goal as calls of pre-bound relation checks; docs/judge.md"),
    },
    "vlm": {
        "thesis": ReporterEntry("capmj.agents.report.vlm:VLMReporter", "front-camera images to a vision-language model"),
    },
}
"""Every reporter, by ``--reporter`` and then ``--reporter-prompt``: ``none`` has no reporter, ``text``
one per prompt, ``vlm`` only the default prompt's.  :func:`capmj.agents.report.make_reporter`
builds them from this table; the names below are its keys."""

REPORTERS: tuple[str, ...] = tuple(REPORTER_TABLE)
"""``--reporter``: ``none``, ``text`` or ``vlm``."""

REPORTER_PROMPTS: tuple[str, ...] = tuple(REPORTER_TABLE["text"])
"""``--reporter-prompt``: the text reporter's prompts, ``thesis`` (the default) first."""

LOOP_POLICIES = ("thesis", "careful")
"""``--loop-policy``: see :mod:`capmj.agents.llm_agent.loop_policy`."""

INTERACTIONS = ("single", "multi")
"""``--interaction``: ``single`` (default: one whole plan per attempt, the thesis's loop) or ``multi``
(turns of code with execution feedback until the model says FINISH: :mod:`capmj.agents.llm_agent.multiturn`)."""

POLICIES = ("code", "tools")
"""``--policy``: ``code`` (default: the model writes Python that calls the planner API) or ``tools`` (the
model calls the API's functions as OpenAI tools, turn by turn: :mod:`capmj.agents.llm_agent.tools`)."""

FEEDBACKS = ("text", "image", "describe")
"""``--feedback`` of ``--interaction multi``: what the model is shown after a turn (``text``, the default:
output, error, API calls, objects; ``image``: also the cameras' RGB views; ``describe``: also a second
model's description of what changed between the views before and after the turn)."""

ON_UNKNOWN = ("replan", "stop")
"""``--on-unknown``: what an unknown reporter verdict does: re-plan like a False verdict (default),
or stop."""


def reporter_prompt_help() -> str:
    """The help of ``--reporter-prompt``: each prompt of the text reporter and what it is."""
    parts = [f"{name} ({entry.about})" for name, entry in REPORTER_TABLE["text"].items()]
    return "the text reporter's prompt: " + ", ".join(parts[:-1]) + " or " + parts[-1]
