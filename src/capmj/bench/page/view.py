"""The page's view of a summary: the capability profile, from ``summary.json``'s ``profile`` when it
has one (:mod:`capmj.bench.profile`), else rebuilt from its per-task cells (older summaries).

A cell is ``{n, successes, success_rate, ci95[, anomalies]}``; a configuration's efficiency is
``{episodes, solved, llm_episodes, total, per_episode, per_solved}`` over :data:`METRICS` — LLM
tokens, cost in USD, LLM calls, turns (a multi-turn episode's turns, else its plan attempts) and
wall seconds.  Per solved episode = total / episodes solved (None when none was); a cost is None
when any episode's price is unknown.  Rebuilt from an older summary, the LLM figures are the
cells' ``llm_usage`` and ``loop`` (None for agents without an LLM) and turns exist only for LLM
episodes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

__all__ = ["METRICS", "ProfileView", "legacy_efficiency", "profile_view"]

METRICS: tuple[tuple[str, str], ...] = (("tokens", "tokens"), ("cost_usd", "$"), ("llm_calls", "LLM calls"),
                                        ("turns", "turns"), ("wall_s", "seconds"))
"""(key, heading) of the efficiency figures, each shown per episode and per solved episode."""


@dataclass(frozen=True)
class ProfileView:
    """Configurations (the first is the baseline), tasks, success cells per configuration and task,
    overall cells, efficiency per configuration, paired comparisons against the baseline, and
    where the numbers came from (``"profile"`` or ``"tasks"``)."""

    configs: tuple[str, ...]
    tasks: tuple[str, ...]
    cells: Mapping[str, Mapping[str, Mapping[str, Any]]]
    overall: Mapping[str, Mapping[str, Any]]
    efficiency: Mapping[str, Mapping[str, Any]]
    paired: tuple[Mapping[str, Any], ...]
    source: str


def legacy_efficiency(cell: Mapping[str, Any]) -> dict[str, Any]:
    """The efficiency of one summary cell of an older summary (``llm_usage``, ``loop``, wall time)."""
    usage = cell.get("llm_usage") or {}
    loop = cell.get("loop") or {}
    llm_eps = int(usage.get("llm_episodes") or 0)
    n, solved = int(cell.get("n") or 0), int(cell.get("successes") or 0)
    cost = usage.get("cost_usd") if usage.get("cost_known", True) else None
    total: dict[str, float | None] = {
        "tokens": float(usage["tokens"]) if llm_eps else None,
        "cost_usd": float(cost) if llm_eps and cost is not None else None,
        "llm_calls": float(usage["calls"]) if llm_eps else None,
        "turns": float(loop["attempts"]) if llm_eps and loop.get("attempts") is not None else None,
        "wall_s": float(cell["wall_s_total"]) if cell.get("wall_s_total") is not None else None,
    }

    def per(d: int) -> dict[str, float | None]:
        return {k: (v / d if v is not None and d else None) for k, v in total.items()}

    return {"episodes": n, "solved": solved, "llm_episodes": llm_eps, "total": total, "per_episode": per(n),
            "per_solved": per(solved)}


def profile_view(summary: Mapping[str, Any]) -> ProfileView:
    """The :class:`ProfileView` of a summary (``summary.json``'s shape)."""
    prof = summary.get("profile")
    if prof:
        return ProfileView(configs=tuple(prof["configs"]), tasks=tuple(prof["tasks"]), cells=prof["cells"],
                           overall=prof["overall"], efficiency=prof["efficiency"],
                           paired=tuple(prof.get("paired") or ()), source="profile")
    configs = tuple(summary["overall"])
    tasks = tuple(sorted(summary["tasks"]))
    cells = {c: {t: summary["tasks"][t][c] for t in tasks if c in summary["tasks"][t]} for c in configs}
    return ProfileView(configs=configs, tasks=tasks, cells=cells, overall=summary["overall"],
                       efficiency={c: legacy_efficiency(summary["overall"][c]) for c in configs},
                       paired=tuple(summary.get("comparisons") or ()), source="tasks")
