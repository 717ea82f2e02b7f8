"""The capability profile: how one model's success changes across configurations, on the same episodes.

:func:`profile` turns records labelled by configuration into ``summary.json``'s ``profile``:
configuration × task success with Wilson intervals over the agent's episodes (anomalies,
:mod:`capmj.bench.anomalies`, are counted beside each cell and left out of its denominator); every
configuration paired against the first on the (task, seed) episodes both ran as the agent's
(exact McNemar, both discordant directions counted, :mod:`capmj.bench.stats`: ``a`` is the first
configuration, ``b`` the other, ``only_a``/``only_b`` the pairs only one of them solved); and the efficiency
columns per episode and per *solved* episode: LLM tokens, cost in USD, LLM calls, turns (attempt
records: a multi-turn episode's turns, else its plan attempts) and wall seconds.  Per solved
episode is the configuration's total over its agent episodes divided by the episodes it solved
(None when it solved none); a cost is None (unknown) when any episode's cost is unknown.
"""

from __future__ import annotations

from typing import Any, Callable, Mapping, Sequence

from capmj.bench.anomalies import denominator, is_anomaly, split
from capmj.bench.spend import usage_of
from capmj.bench.stats import paired_comparison, wilson
from capmj.records import EpisodeRecord

SCHEMA = "capmj.profile/1"
EFFICIENCY = ("tokens", "cost_usd", "llm_calls", "turns", "wall_s")
"""The efficiency columns, per episode and per solved episode."""


def cell(records: Sequence[EpisodeRecord]) -> dict[str, Any]:
    """Success of one configuration on some episodes: ``n`` (the agent's episodes), ``successes``,
    ``success_rate``, ``ci95`` (Wilson), ``anomalies`` and ``denominator`` (the text printed beside the rate)."""
    agent, anomalies = split(records)
    k = sum(1 for r in agent if r.success)
    n = len(agent)
    lo, hi = wilson(k, n)
    return {"n": n, "successes": k, "success_rate": k / n if n else None, "ci95": [lo, hi],
            "anomalies": len(anomalies), "denominator": f"{k}/" + denominator(n, len(anomalies))}


def _turns(r: EpisodeRecord) -> int:
    return len(r.llm_attempts) or r.attempts


def efficiency(records: Sequence[EpisodeRecord]) -> dict[str, Any]:
    """Totals, per-episode and per-solved-episode means of :data:`EFFICIENCY` over the agent's episodes."""
    agent, _ = split(records)
    solved = sum(1 for r in agent if r.success)
    uses = [usage_of(r) for r in agent]
    known = all(u is None or isinstance(u["cost_usd"], (int, float)) for u in uses)
    totals: dict[str, float | None] = {
        "tokens": float(sum(u["tokens"] for u in uses if u is not None)),
        "cost_usd": sum(float(u["cost_usd"]) for u in uses if u is not None) if known else None,
        "llm_calls": float(sum(u["calls"] for u in uses if u is not None)),
        "turns": float(sum(_turns(r) for r in agent)),
        "wall_s": sum(float(r.wall_s or 0.0) for r in agent),
    }

    def per(d: int) -> dict[str, float | None]:
        return {k: (v / d if v is not None and d else None) for k, v in totals.items()}

    return {"episodes": len(agent), "solved": solved, "llm_episodes": sum(u is not None for u in uses),
            "total": totals, "per_episode": per(len(agent)), "per_solved": per(solved)}


def profile(records: Sequence[EpisodeRecord], label_of: Callable[[EpisodeRecord], str],
            order: Sequence[str] | None = None) -> dict[str, Any]:
    """``summary.json``'s ``profile`` (see the module docstring and docs/bench.md).

    ``order`` lists the configurations (the first is the baseline every other is paired against);
    by default, in the order their first record appears."""
    configs: list[str] = list(order or [])
    by: dict[str, dict[str, list[EpisodeRecord]]] = {}
    for r in records:
        lab = label_of(r)
        if lab not in configs:
            configs.append(lab)
        by.setdefault(lab, {}).setdefault(r.task, []).append(r)
    tasks = sorted({r.task for r in records})
    cells = {c: {t: cell(by.get(c, {}).get(t, [])) for t in tasks if by.get(c, {}).get(t)} for c in configs}
    every = {c: [r for rs in by.get(c, {}).values() for r in rs] for c in configs}
    agent_only = [r for r in records if not is_anomaly(r)]
    paired = [paired_comparison(agent_only, label_of, configs[0], other) for other in configs[1:]]
    return {
        "schema": SCHEMA,
        "configs": configs,
        "baseline": configs[0] if configs else None,
        "tasks": tasks,
        "cells": cells,
        "overall": {c: cell(every[c]) for c in configs},
        "efficiency": {c: efficiency(every[c]) for c in configs},
        "paired": paired,
    }


def efficiency_rows(prof: Mapping[str, Any]) -> list[str]:
    """The efficiency table of ``summary.md`` (per episode, then per solved episode)."""
    def fmt(v: float | None, nd: int) -> str:
        return "—" if v is None else f"{v:,.{nd}f}"

    out = ["| Configuration | success | tokens/ep | $/ep | LLM calls/ep | turns/ep | s/ep | tokens/solved | "
           "$/solved | LLM calls/solved | turns/solved | s/solved |",
           "|---|---|" + "---:|" * 10]
    for c in prof["configs"]:
        e = prof["efficiency"][c]
        pe, ps = e["per_episode"], e["per_solved"]
        out.append(f"| {c} | {prof['overall'][c]['denominator']} | {fmt(pe['tokens'], 0)} | {fmt(pe['cost_usd'], 4)} | "
                   f"{fmt(pe['llm_calls'], 1)} | {fmt(pe['turns'], 2)} | {fmt(pe['wall_s'], 1)} | "
                   f"{fmt(ps['tokens'], 0)} | {fmt(ps['cost_usd'], 4)} | {fmt(ps['llm_calls'], 1)} | "
                   f"{fmt(ps['turns'], 2)} | {fmt(ps['wall_s'], 1)} |")
    return out


__all__ = ["EFFICIENCY", "SCHEMA", "cell", "efficiency", "efficiency_rows", "profile"]
