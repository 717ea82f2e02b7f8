"""How well a reporter's verdicts match the labels: the figures of ``summary.json``.

"Positive" means *goal achieved* (the label True), so recall is the share of achieved states the
reporter calls achieved (a miss is a needless re-plan in the loop), specificity the share of
failed states it calls failed (a miss stops the loop too early), precision the share of its
"achieved" verdicts that are right.  An **unknown** verdict (no bool reached) is never right: it
counts against accuracy, recall and specificity, and ``verdict_rate`` says how often it happened.
Balanced accuracy, the mean of recall and specificity, is the headline figure because the set
has more negatives than positives: an always-"no" reporter scores its negative share in accuracy
but 0.5 here.  Every proportion comes with its 95 % Wilson interval.  ``high_confidence`` counts the
verdicts :func:`capmj.agents.report.confidence.assess` trusts (the ones the ``careful`` loop acts on) and
``high_confidence_accuracy`` is their share of right answers.

Balanced accuracy can hide a reporter that does not look at the scene: one that answers each goal
the same way whatever the state scores 0.5 per task and can look fair overall.  So each group also
counts its **contrasts**, the (task, seed) episodes with both an achieved and a failed state judged:
``contrasts_told_apart`` is the number whose every achieved state got True and every failed state
False, ``contrasts_state_blind`` the number whose states all got the same verdict (unknown included):
a reporter whose verdict follows the goal, not the state, shows here (``docs/judge.md`` has the case).
"""

from __future__ import annotations

from typing import Any, Callable, Iterable, Mapping, Sequence

from capmj.agents.choices import REPORTER_PROMPTS
from capmj.agents.report.verdict import SOURCES
from capmj.bench.results import wilson

__all__ = ["RECORD_FIELDS", "confusion", "contrast_counts", "group_metrics", "metrics"]

RECORD_FIELDS: dict[str, str] = {
    "task": "task name", "seed": "episode seed", "case": "case name within (task, seed)",
    "kind": "oracle, displaced, unstacked, toppled, swapped, wrong_bowl, toppled_out, near_inside, near_outside (or run)",
    "label": "ground truth: the task predicate's success on the state", "reporter": "the reporter's label",
    "reporter_prompt": f"the text reporter's prompt: {', '.join(REPORTER_PROMPTS)} (--reporter-prompt)",
    "verdict": "the reporter's verdict: true, false or null (unknown)",
    "source": "where the verdict came from: code, repair, direct, unknown (or predicate)",
    "reason": "the reporter's reason", "wrong": "objects it names as wrong",
    "errors": "problems met on the way to the verdict",
    "confidence": "high / low (capmj.agents.report.confidence.assess; null without an LLM answer)",
    "low_confidence": "why it is low (a key of capmj.agents.report.confidence.LOW_CONFIDENCE), else null",
    "predicate": "the predicate re-evaluated on the state as judged (must equal label)",
    "correct": "verdict == label", "calls": "LLM calls", "cached_calls": "of which from the cache",
    "prompt_tokens": "prompt tokens", "completion_tokens": "completion tokens",
    "cost_usd": "nominal cost (null when the price is unknown)", "wall_s": "seconds", "error": "what failed, else null",
}
"""The keys of every line of ``judged.jsonl`` and their meaning."""


def _rate(k: int, n: int) -> float | None:
    return k / n if n else None


def _ci(k: int, n: int) -> list[float] | None:
    return [round(v, 4) for v in wilson(k, n)] if n else None


def confusion(records: Iterable[Mapping[str, Any]]) -> dict[str, int]:
    """Counts: tp (achieved, said achieved), fn (achieved, said not), fp, tn, and unknown verdicts
    on positives (``unknown_pos``) and negatives (``unknown_neg``)."""
    c = {"tp": 0, "fn": 0, "fp": 0, "tn": 0, "unknown_pos": 0, "unknown_neg": 0}
    for r in records:
        label, verdict = bool(r["label"]), r.get("verdict")
        if verdict is None:
            c["unknown_pos" if label else "unknown_neg"] += 1
        elif label:
            c["tp" if verdict else "fn"] += 1
        else:
            c["fp" if verdict else "tn"] += 1
    return c


def contrast_counts(records: Iterable[Mapping[str, Any]]) -> dict[str, int]:
    """``contrasts``, ``contrasts_told_apart`` and ``contrasts_state_blind`` (see the module docstring)."""
    episodes: dict[tuple[str, int], list[Mapping[str, Any]]] = {}
    for r in records:
        episodes.setdefault((str(r.get("task")), int(r.get("seed") or 0)), []).append(r)
    c = {"contrasts": 0, "contrasts_told_apart": 0, "contrasts_state_blind": 0}
    for recs in episodes.values():
        if len({bool(r["label"]) for r in recs}) < 2:
            continue
        c["contrasts"] += 1
        c["contrasts_told_apart"] += all(r.get("verdict") is bool(r["label"]) for r in recs)
        c["contrasts_state_blind"] += len({r.get("verdict") for r in recs}) == 1
    return c


def metrics(records: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """The figures of one group of judged states (see the module docstring); None where undefined."""
    c = confusion(records)
    pos = c["tp"] + c["fn"] + c["unknown_pos"]
    neg = c["fp"] + c["tn"] + c["unknown_neg"]
    n = pos + neg
    said_yes = c["tp"] + c["fp"]
    reached = n - c["unknown_pos"] - c["unknown_neg"]
    recall, specificity = _rate(c["tp"], pos), _rate(c["tn"], neg)
    sources = {s: 0 for s in (*SOURCES, "predicate")}
    for r in records:
        src = str(r.get("source") or "unknown")
        sources[src] = sources.get(src, 0) + 1
    cost = [r.get("cost_usd") for r in records]
    high = [r for r in records if r.get("confidence") == "high"]
    return {
        "n": n, "positives": pos, "negatives": neg, **c,
        "accuracy": _rate(c["tp"] + c["tn"], n), "accuracy_ci": _ci(c["tp"] + c["tn"], n),
        "balanced_accuracy": (recall + specificity) / 2 if recall is not None and specificity is not None else None,
        "precision": _rate(c["tp"], said_yes), "precision_ci": _ci(c["tp"], said_yes),
        "recall": recall, "recall_ci": _ci(c["tp"], pos),
        "specificity": specificity, "specificity_ci": _ci(c["tn"], neg),
        "positive_share": _rate(pos, n),
        "verdict_rate": _rate(reached, n), "verdict_rate_ci": _ci(reached, n),
        "verdict_sources": {k: v for k, v in sources.items() if v or k in SOURCES},
        **contrast_counts(records),
        "high_confidence": len(high),
        "high_confidence_accuracy": _rate(sum(1 for r in high if r.get("correct")), len(high)),
        "label_mismatches": sum(1 for r in records if r.get("predicate") is not None and r["predicate"] != r["label"]),
        "errors": sum(1 for r in records if r.get("error")),
        "calls": sum(int(r.get("calls") or 0) for r in records),
        "cached_calls": sum(int(r.get("cached_calls") or 0) for r in records),
        "prompt_tokens": sum(int(r.get("prompt_tokens") or 0) for r in records),
        "completion_tokens": sum(int(r.get("completion_tokens") or 0) for r in records),
        "cost_usd": None if any(v is None for v in cost) else round(sum(float(v or 0) for v in cost), 8),
    }


def group_metrics(records: Sequence[Mapping[str, Any]], key: Callable[[Mapping[str, Any]], str]) -> dict[str, Any]:
    """:func:`metrics` per value of ``key`` (e.g. per task, per kind), keys in first-seen order."""
    groups: dict[str, list[Mapping[str, Any]]] = {}
    for r in records:
        groups.setdefault(key(r), []).append(r)
    return {k: metrics(v) for k, v in groups.items()}
