"""LLM usage and cost of episodes, per task and overall, and the run-level budget.

Per episode the LLM agent records its nominal usage in ``llm.spend`` (see
:mod:`capmj.agents.lmp.meter`): tokens, and a cost in USD that is ``None`` when the model's price
is unknown.  Totals add up tokens always, and cost only while every episode's cost is known — one
unknown price makes the total unknown (shown as "unknown", never as 0).  Records without
``llm.spend`` (older runs) have known tokens but unknown cost.

:class:`RunBudget` stops a grid when the episodes of the whole result folder (earlier,
resumed-from invocations included) used more than ``--max-tokens`` / ``--max-cost-usd``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Iterable, Mapping, Sequence

from capmj.agents.factory import agent_setting
from capmj.agents.lmp.meter import price_source
from capmj.errors import ConfigError
from capmj.records import Episode

__all__ = ["BudgetTracker", "RunBudget", "fmt_cost", "usage", "usage_of"]


def usage_of(rec: Episode) -> dict[str, Any] | None:
    """``{"calls", "tokens", "cost_usd"}`` of one episode; None for an episode without an LLM."""
    llm = rec.llm
    if llm is None:
        return None
    if llm.spend is not None:
        return {"calls": llm.spend.calls, "tokens": llm.spend.tokens, "cost_usd": llm.spend.cost_usd}
    return {"calls": llm.calls, "tokens": llm.prompt_tokens + llm.completion_tokens, "cost_usd": None}


def usage(records: Iterable[Episode]) -> dict[str, Any]:
    """Totals and per-episode means; ``cost_usd`` None (unknown) if any episode's cost is unknown."""
    per = [u for u in (usage_of(r) for r in records) if u is not None]
    if not per:
        return {"llm_episodes": 0, "calls": 0, "tokens": 0, "cost_usd": 0.0, "cost_known": True,
                "tokens_mean": None, "cost_usd_mean": None}
    known = all(isinstance(u["cost_usd"], (int, float)) for u in per)
    cost = sum(float(u["cost_usd"]) for u in per) if known else None
    tokens = sum(u["tokens"] for u in per)
    return {"llm_episodes": len(per), "calls": sum(u["calls"] for u in per), "tokens": tokens,
            "cost_usd": cost, "cost_known": known, "tokens_mean": tokens / len(per),
            "cost_usd_mean": cost / len(per) if cost is not None else None}


def fmt_cost(v: float | None) -> str:
    return "unknown" if v is None else f"{v:.4f}"


@dataclass(frozen=True)
class RunBudget:
    """Limits on the whole run folder's LLM usage; ``None`` = no limit."""

    max_cost_usd: float | None = None
    max_tokens: int | None = None

    def __post_init__(self) -> None:
        for name, v in (("--max-cost-usd", self.max_cost_usd), ("--max-tokens", self.max_tokens)):
            if v is not None and not (v > 0 and math.isfinite(v)):
                raise ConfigError(f"{name} must be positive, got {v}")

    @classmethod
    def resolve(cls, max_cost_usd: float | None, max_tokens: int | None,
                stored: Mapping[str, Any] | None = None) -> "RunBudget":
        """Limits from the command line, else those stored in the run's config.json (resume)."""
        stored = stored or {}
        return cls(max_cost_usd if max_cost_usd is not None else stored.get("max_cost_usd"),
                   max_tokens if max_tokens is not None else stored.get("max_tokens"))

    def as_dict(self) -> dict[str, Any]:
        return {"max_cost_usd": self.max_cost_usd, "max_tokens": self.max_tokens}

    def check_price(self, agent: Any) -> None:
        """ConfigError when a cost cap is asked for a model whose price is unknown."""
        if self.max_cost_usd is None:
            return
        model = getattr(agent, "model", None)
        if model is None:
            raise ConfigError("--max-cost-usd limits LLM spending; this agent makes no LLM calls")
        if price_source(model, agent_setting(agent, "price")) == "unknown":
            raise ConfigError(f"--max-cost-usd needs a price, but the price of {model!r} is unknown; "
                              "declare one with --price IN,OUT (USD per million tokens) or use --max-tokens")

    @property
    def active(self) -> bool:
        return self.max_cost_usd is not None or self.max_tokens is not None

    def exceeded(self, records: Iterable[Episode]) -> str | None:
        """Why the run must stop (a sentence), or None while it is within its limits."""
        u = usage(records)
        if self.max_tokens is not None and u["tokens"] >= self.max_tokens:
            return f"the run used {u['tokens']} LLM tokens (--max-tokens {self.max_tokens})"
        if self.max_cost_usd is not None:
            if u["cost_usd"] is None:
                return "the run's LLM cost is unknown (a model without a price), so --max-cost-usd cannot be kept"
            if u["cost_usd"] >= self.max_cost_usd:
                return f"the run cost {u['cost_usd']:.6f} USD (--max-cost-usd {self.max_cost_usd:g})"
        return None


class BudgetTracker:
    """The grid's stop condition: records of the folder so far, checked before each new episode."""

    def __init__(self, budget: RunBudget, existing: Sequence[Episode]) -> None:
        self.budget = budget
        self.records: list[Episode] = list(existing)
        self.reason: str | None = None

    def add(self, rec: Episode) -> None:
        self.records.append(rec)

    def stop(self) -> bool:
        if self.budget.active and self.reason is None:
            self.reason = self.budget.exceeded(self.records)
        return self.reason is not None
