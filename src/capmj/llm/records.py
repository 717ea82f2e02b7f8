"""The records of LLM calls: one answer (:class:`Completion`), the accounting of one call, failed
or not (:class:`CallRecord`), and a client's totals (:class:`Usage`).

Frozen values, so an episode can keep them in its record and a report can sum them without
worrying that a later call changes what an earlier one said.
"""

from __future__ import annotations

from dataclasses import dataclass

@dataclass(frozen=True)
class Completion:
    """One answer.  A cache hit carries the stored tokens/cost, ``cached=True``, ``attempts=0``."""

    text: str
    model: str
    prompt_tokens: int
    completion_tokens: int
    cost_usd: float
    latency_s: float
    cached: bool
    attempts: int
    purpose: str
    cut: str | None = None
    """``"repetition"`` when the answer ended in a repetition loop that was cut (see
    :func:`capmj.llm.stream.repetition_cut`); else None."""


@dataclass(frozen=True)
class CallRecord:
    """Accounting for one ``complete`` call, successful (``error is None``) or not; ``partial`` is
    the text a stalled or broken stream had delivered before the call failed."""

    purpose: str
    model: str
    prompt_tokens: int
    completion_tokens: int
    cost_usd: float
    latency_s: float
    cached: bool
    attempts: int
    error: str | None = None
    partial: str | None = None
    cut: str | None = None


@dataclass(frozen=True)
class Usage:
    """Totals over a client's calls.  ``cost_usd`` counts money actually spent: not cache hits."""

    calls: int
    cached_calls: int
    failed_calls: int
    prompt_tokens: int
    completion_tokens: int
    cost_usd: float
    latency_s: float
