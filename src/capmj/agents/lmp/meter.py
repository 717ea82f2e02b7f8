"""Metering of an episode's LLM calls: tokens, cost (or *unknown*), budgets, and the call log.

Every LMP call of the LLM agent goes through a callable made by :meth:`LLMMeter.wrap`, which

* keeps the call (messages sent, completion received, tokens, cost, cache hit) for the result
  folder's transcripts (``python -m capmj.bench export`` turns them into fine-tuning data);
* adds up tokens and cost, and stops the episode with :class:`LLMBudgetExceeded` once its
  ``episode_max_tokens`` / ``episode_max_cost_usd`` is exceeded.

Why *nominal* usage (cache hits counted at their stored tokens and cost): a budget must stop an
episode at the same call whether the answers come from the provider or from the cache, or a
replay from the cache would not reproduce the run.  Money actually paid (live calls only) is the
client's ``cost_usd`` in the episode's ``llm`` record.

Prices: a declared price (:class:`Price`, USD per million input/output tokens, for self-hosted or
unlisted models) wins; else litellm's local price list when it knows the model; else the cost is
*unknown* (``None``), never 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

from capmj.errors import ConfigError, LLMBudgetExceeded
from capmj.llm.provider import import_litellm
from capmj.records import Spend, SpendLimits

__all__ = ["LLMBudgetExceeded", "LLMMeter", "Price", "check_limit", "check_limits", "parse_price", "price_source"]


@dataclass(frozen=True)
class Price:
    """USD per million prompt (input) and completion (output) tokens."""

    input_per_mtok: float
    output_per_mtok: float

    def cost(self, prompt_tokens: int, completion_tokens: int) -> float:
        return (prompt_tokens * self.input_per_mtok + completion_tokens * self.output_per_mtok) / 1e6


def parse_price(text: str | Price | None) -> Price | None:
    """``"0.15,0.6"`` (USD per million input, output tokens) -> :class:`Price`."""
    if text is None or isinstance(text, Price):
        return text
    parts = str(text).split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 2 or not all(math.isfinite(v) and v >= 0 for v in values):
        raise ConfigError(f"bad price {text!r}: give USD per million input and output tokens, e.g. 0.15,0.6")
    return Price(*values)


def price_source(model: str, declared: Price | None = None) -> str:
    """``"declared"``, ``"litellm"`` (its local price list knows ``model``) or ``"unknown"``."""
    if declared is not None:
        return "declared"
    try:
        info = import_litellm().get_model_info(model)
    except Exception:  # noqa: BLE001 - litellm raises for models it does not list
        return "unknown"
    known = info.get("input_cost_per_token") is not None and info.get("output_cost_per_token") is not None
    return "litellm" if known else "unknown"


def check_limit(value: Any, name: str, kind: type) -> Any:
    """``kind(value)`` when it is a positive finite number (None stays None), else ConfigError naming ``name``."""
    if value is None:
        return None
    try:
        v = kind(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a positive number, got {value!r}") from None
    if not (v > 0 and math.isfinite(v)):
        raise ConfigError(f"{name} must be a positive number, got {value!r}")
    return v


def check_limits(model: str, *, max_tokens: Any = None, max_cost_usd: Any = None,
                 price: Price | None = None) -> tuple[int | None, float | None]:
    """The episode limits, validated: positive numbers, and a cost cap only with a known price."""
    tokens = check_limit(max_tokens, "episode_max_tokens", int)
    cost = check_limit(max_cost_usd, "episode_max_cost_usd", float)
    if cost is not None and price_source(model, price) == "unknown":
        raise ConfigError(f"episode_max_cost_usd needs a price, but the price of {model!r} is unknown; "
                          "declare one (price 'IN,OUT' in USD per million tokens) or cap tokens instead")
    return tokens, cost


class LLMMeter:
    """Meters ``complete(messages, purpose=...)`` callables (``LLMClient.complete``) of one episode."""

    def __init__(self, model: str, *, max_tokens: int | None = None, max_cost_usd: float | None = None,
                 price: Price | None = None, source: str | None = None) -> None:
        self.max_tokens, self.max_cost_usd = check_limits(model, max_tokens=max_tokens, max_cost_usd=max_cost_usd,
                                                          price=price)
        self.price = price
        self.model = model
        self._source = source
        self.calls: list[dict[str, Any]] = []
        self.attempt = 1
        self.prompt_tokens = 0
        self.completion_tokens = 0
        self.cost_usd = 0.0
        self.exceeded: LLMBudgetExceeded | None = None

    @property
    def source(self) -> str:
        """Where prices come from (looked up on first use: importing litellm takes seconds)."""
        if self._source is None:
            self._source = price_source(self.model, self.price)
        return self._source

    @property
    def tokens(self) -> int:
        return self.prompt_tokens + self.completion_tokens

    def _over(self) -> str | None:
        if self.max_tokens is not None and self.tokens > self.max_tokens:
            return f"LLM token budget of {self.max_tokens} tokens per episode exceeded ({self.tokens} used)"
        if self.max_cost_usd is not None and self.cost_usd > self.max_cost_usd:
            return (f"LLM cost budget of {self.max_cost_usd:g} USD per episode exceeded "
                    f"({self.cost_usd:.6f} USD used)")
        return None

    def wrap(self, complete: Callable[..., Any]) -> Callable[..., Any]:
        """``complete`` metered: logged, counted, and refused once the episode is over budget."""
        def metered(messages: Any, *, purpose: str = "", **kwargs: Any) -> Any:
            return self._call(complete, messages, purpose, kwargs)

        return metered

    def _call(self, complete: Callable[..., Any], messages: Any, purpose: str, kwargs: dict[str, Any]) -> Any:
        if self.exceeded is not None:
            raise LLMBudgetExceeded(str(self.exceeded))
        completion = complete(messages, purpose=purpose, **kwargs)
        pt, ct = int(completion.prompt_tokens), int(completion.completion_tokens)
        if self.price is not None:
            cost: float | None = self.price.cost(pt, ct)
        elif self.source == "litellm":
            cost = float(completion.cost_usd)
        else:
            cost = None
        self.prompt_tokens += pt
        self.completion_tokens += ct
        self.cost_usd += cost or 0.0
        self.calls.append({"attempt": self.attempt, "purpose": purpose, "messages": [dict(m) for m in messages],
                           "completion": completion.text, "cached": bool(completion.cached),
                           "prompt_tokens": pt, "completion_tokens": ct, "cost_usd": cost})
        problem = self._over()
        if problem is not None:
            self.exceeded = LLMBudgetExceeded(problem)
            raise LLMBudgetExceeded(problem)
        return completion

    def summary(self) -> Spend:
        """Nominal usage of the episode (``cost_usd`` None when the price is unknown)."""
        return Spend(calls=len(self.calls), prompt_tokens=self.prompt_tokens,
                     completion_tokens=self.completion_tokens, tokens=self.tokens,
                     cost_usd=None if self.source == "unknown" else round(self.cost_usd, 10),
                     price_source=self.source, limits=SpendLimits(self.max_tokens, self.max_cost_usd),
                     exceeded=str(self.exceeded) if self.exceeded is not None else None)
