"""The records of LLM calls: one answer (:class:`Completion`), the accounting of one call, failed
or not (:class:`CallRecord`), and a client's totals (:class:`Usage`).

Frozen values, so an episode can keep them in its record and a report can sum them without
worrying that a later call changes what an earlier one said.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ToolCall:
    """One function call a model asked for in OpenAI's ``tool_calls`` form: the provider's ``id``
    (what the ``tool`` message answering it names), the function's ``name`` and its ``arguments``
    as the JSON text the model wrote (parsed by the caller, which reports bad JSON)."""

    id: str
    name: str
    arguments: str

    def to_message(self) -> dict[str, object]:
        """The call as an assistant message's ``tool_calls`` entry (OpenAI chat format)."""
        return {"id": self.id, "type": "function", "function": {"name": self.name, "arguments": self.arguments}}


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
    tool_calls: tuple[ToolCall, ...] = ()
    """The function calls of an answer to a request that offered ``tools``, in order (an answer
    with calls may have no text)."""


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
    tool_calls: int = 0
    """Function calls in the answer (requests with ``tools`` only)."""


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
