"""What the LLM agent records about an episode (``llm`` of a result): its options, usage, spend and
attempts.

Why typed: these keys were written by the agent key by key and read back by four modules with
``.get`` fallbacks, so a renamed key failed silently.  Now the agent builds an :class:`LLMNotes` and
the readers use its attributes; a stored line that does not match is a
:class:`~capmj.errors.RecordError`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from capmj.records.attempt import AttemptRecord
from capmj.records.codec import from_plain, to_plain

__all__ = ["ANSWERED", "LLMNotes", "Spend", "SpendLimits", "TURNS_USED_UP"]

TURNS_USED_UP = "turns used up"
"""``LLMNotes.stopped`` of a multi-turn episode that reached its ``max_turns`` without the model's
FINISH (failure label ``no_finish``, :mod:`capmj.bench.failures`); under ``--policy tools``, one whose
model called functions in every turn."""

ANSWERED = "model: no tool call"
"""``LLMNotes.stopped`` of a ``--policy tools`` episode whose model answered without a function call
(without saying FINISH): its claim that it is done."""


@dataclass(frozen=True)
class SpendLimits:
    """The episode's LLM limits (None: none)."""

    tokens: int | None = None
    cost_usd: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return to_plain(self)

    @classmethod
    def from_dict(cls, data: Any, *, strict: bool = True) -> "SpendLimits":
        return from_plain(cls, data, strict=strict)


@dataclass(frozen=True)
class Spend:
    """Nominal LLM usage of one episode (:meth:`capmj.agents.lmp.meter.LLMMeter.summary`):
    ``cost_usd`` is None when the model's price is unknown."""

    calls: int = 0
    prompt_tokens: int = 0
    completion_tokens: int = 0
    tokens: int = 0
    cost_usd: float | None = None
    price_source: str = "unknown"
    limits: SpendLimits = SpendLimits()
    exceeded: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return to_plain(self)

    @classmethod
    def from_dict(cls, data: Any, *, strict: bool = True) -> "Spend":
        return from_plain(cls, data, strict=strict)


@dataclass(frozen=True)
class LLMNotes:
    """The LLM agent's record of one episode: options, client usage, why it stopped, attempts."""

    model: str
    reporter: str = "none"
    max_attempts: int = 1
    on_unknown: str = "replan"
    loop_policy: str = "thesis"
    reporter_prompt: str = "thesis"
    temperature: float = 0.0
    replan_temperature: float = 0.0
    replan_retries: int = 0
    attempts: tuple[AttemptRecord, ...] = ()
    calls: int = 0
    cached_calls: int = 0
    failed_calls: int = 0
    prompt_tokens: int = 0
    completion_tokens: int = 0
    cost_usd: float = 0.0
    latency_s: float = 0.0
    stopped: str | None = None
    spend: Spend | None = None
    interaction: str | None = None
    """``multi`` for a multi-turn episode (each attempt record is a turn); None (absent): single-turn."""
    feedback: str | None = None
    """Multi-turn: ``text``, ``image`` or ``describe``."""
    max_turns: int | None = None
    """Multi-turn: the turn limit."""
    finish_agreed: bool | None = None
    """Multi-turn: whether the task predicate held when the model said FINISH (its self-assessment,
    like a reporter's verdict); None when it never said FINISH.  Under ``--policy tools`` an answer
    without a function call is such a claim too."""
    policy: str | None = None
    """``tools`` when the model called the API as functions (each attempt record is a turn); None
    (absent): code."""

    OMIT_IF_NONE: ClassVar[frozenset[str]] = frozenset({"stopped", "spend", "interaction", "feedback", "max_turns",
                                                         "finish_agreed", "policy"})
    """Keys absent until the loop stops / the episode's spend is summed up (an agent that raised
    before that); the multi-turn keys (issue #47) absent from single-turn records, which stay as
    they were written before."""
    DEFAULT_IF_MISSING: ClassVar[frozenset[str]] = frozenset({"loop_policy", "reporter_prompt"})
    """Added with issue #26's loop policies and reporter prompts; older lines ran the thesis's."""

    def to_dict(self) -> dict[str, Any]:
        return to_plain(self)

    @classmethod
    def from_dict(cls, data: Any, *, strict: bool = True) -> "LLMNotes":
        return from_plain(cls, data, strict=strict)
