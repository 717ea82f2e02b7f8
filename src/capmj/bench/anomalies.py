"""Harness failures apart from agent failures: which failure labels are *anomalies*.

An anomaly is an episode whose outcome says nothing about the agent: the LLM provider failed after
the client's retries (an HTTP error, a quota or rate limit, a server that never answered, no text
in the answer, a cache-only run without the entry), or capmj itself could not run or judge the
episode (a worker that died, a result that could not be returned, a task that failed to load or
build its scene, an evaluation that raised).  Anomalies are counted and listed in every summary
and left out of the agent's denominator; every other failure label is the agent's.

:data:`SIDE` classifies every label of :data:`capmj.bench.failures.LABELS` (a test checks that none
is missing); :func:`is_anomaly` reads a record's label.
"""

from __future__ import annotations

from typing import Any, Iterable, Mapping, Sequence

from capmj.bench.failures import LABELS
from capmj.records import EpisodeRecord

AGENT = "agent"
ANOMALY = "anomaly"

SIDE: dict[str, str] = {
    "no_code": AGENT, "syntax": AGENT, "sandbox_violation": AGENT, "budget": AGENT, "unknown_object": AGENT,
    "api_misuse": AGENT, "plan_exception": AGENT, "helper_lmp": AGENT, "perception": AGENT, "motion": AGENT,
    "collision": AGENT, "physics": AGENT, "wrong_plan": AGENT, "reporter_false_positive": AGENT, "reporter_false_negative": AGENT,
    "no_finish": AGENT,
    "llm_error": ANOMALY, "infrastructure": ANOMALY,
}
"""Each failure label: the agent's failure, or an anomaly of the harness (see the module docstring).

``budget`` is the agent's: the episode's own LLM or sandbox budget, which the agent spent;
``perception``, ``collision`` and ``physics`` are the agent's configuration's (what it reads, where
its moves went, what its plan built)."""

ANOMALY_LABELS: tuple[str, ...] = tuple(lab for lab in LABELS if SIDE.get(lab) == ANOMALY)

DEFAULT_THRESHOLD = 0.10
"""Anomaly share of a run above which its summary's first line says so (``--anomaly-threshold``)."""


def is_anomaly(rec: EpisodeRecord) -> bool:
    """True when the episode failed for a reason that is not the agent's."""
    return not rec.success and rec.failure is not None and SIDE.get(rec.failure) == ANOMALY


def split(records: Iterable[EpisodeRecord]) -> tuple[list[EpisodeRecord], list[EpisodeRecord]]:
    """(the agent's episodes, the anomalies)."""
    agent: list[EpisodeRecord] = []
    anomalies: list[EpisodeRecord] = []
    for r in records:
        (anomalies if is_anomaly(r) else agent).append(r)
    return agent, anomalies


def listing(records: Sequence[EpisodeRecord], label_of: Any = None) -> list[dict[str, Any]]:
    """One entry per anomaly: configuration label, task, seed, failure label, error text."""
    out = []
    for r in records:
        if is_anomaly(r):
            out.append({"config": label_of(r) if label_of is not None else r.config, "task": r.task,
                        "seed": r.seed, "label": r.failure, "error": r.error})
    return sorted(out, key=lambda a: (str(a["config"]), a["task"], a["seed"]))


def section(records: Sequence[EpisodeRecord], threshold: float, label_of: Any = None) -> dict[str, Any]:
    """``summary.json``'s ``anomalies``: count, share of all episodes, the threshold and whether it
    was exceeded, counts by label and the list (:func:`listing`)."""
    n = len(records)
    found = listing(records, label_of)
    labels: dict[str, int] = {}
    for a in found:
        labels[a["label"]] = labels.get(a["label"], 0) + 1
    share = len(found) / n if n else 0.0
    return {"count": len(found), "episodes": n, "share": share, "threshold": threshold,
            "exceeded": share > threshold, "labels": labels, "list": found}


def headline(anomalies: Mapping[str, Any]) -> str | None:
    """The first line of a summary whose anomaly share exceeds its threshold (None otherwise)."""
    if not anomalies.get("exceeded"):
        return None
    labels = ", ".join(f"{k} {v}" for k, v in anomalies["labels"].items())
    return (f"WARNING: {anomalies['count']} of {anomalies['episodes']} episodes "
            f"({round(100 * anomalies['share'])} %) are anomalies ({labels}), above the "
            f"{round(100 * anomalies['threshold'])} % threshold: these are harness failures, not the agent's, "
            "and are excluded from every rate below")


def denominator(n_agent: int, n_anomalies: int) -> str:
    """``"12/18 episodes, 2 anomalies excluded"``-style text of a rate's denominator (without the successes)."""
    text = f"{n_agent} episode" + ("s" if n_agent != 1 else "")
    if n_anomalies:
        text += f", {n_anomalies} anomal{'ies' if n_anomalies != 1 else 'y'} excluded"
    return text


__all__ = ["AGENT", "ANOMALY", "ANOMALY_LABELS", "DEFAULT_THRESHOLD", "SIDE", "denominator", "headline",
           "is_anomaly", "listing", "section", "split"]
