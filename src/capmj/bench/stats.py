"""Paired comparison of two configurations on the same (task, seed) pairs: exact McNemar test.

Why McNemar and not two Wilson intervals: both configurations ran the *same* scenes, so their
outcomes are paired; only the discordant pairs (one succeeded, the other failed) carry evidence
about which is better.  With ``b`` pairs where A alone succeeded and ``c`` where B alone did, the
exact two-sided test gives ``p = min(1, 2 * P[X <= min(b, c)])`` for ``X ~ Binomial(b + c, 1/2)``
(``p = 1`` when there is no discordant pair).  Exact, because benchmark cells are small (n = 50
seeds, often a handful of discordant pairs) where the chi-squared approximation is poor.
"""

from __future__ import annotations

import math
from math import comb
from typing import Any, Callable, Sequence, TypeVar

from capmj.records import Episode

R = TypeVar("R", bound=Episode)

__all__ = ["ALPHA", "mcnemar_exact", "paired_comparison", "wilson"]

ALPHA = 0.05
"""Differences with p >= ALPHA are flagged as not significant."""


def mcnemar_exact(b: int, c: int) -> float:
    """Two-sided exact McNemar p-value for ``b`` and ``c`` discordant pairs."""
    if b < 0 or c < 0:
        raise ValueError("discordant counts must be >= 0")
    n = b + c
    if n == 0:
        return 1.0
    k = min(b, c)
    tail = sum(comb(n, i) for i in range(k + 1)) / 2 ** n
    return min(1.0, 2.0 * tail)


def _cell(pairs: Sequence[tuple[bool, bool]]) -> dict[str, Any]:
    n = len(pairs)
    a = sum(1 for x, _ in pairs if x)
    b_ = sum(1 for _, y in pairs if y)
    only_a = sum(1 for x, y in pairs if x and not y)
    only_b = sum(1 for x, y in pairs if y and not x)
    p = mcnemar_exact(only_a, only_b)
    return {"n": n, "successes_a": a, "successes_b": b_, "only_a": only_a, "only_b": only_b,
            "difference": (a - b_) / n if n else None, "p_value": p, "significant": p < ALPHA}


def paired_comparison(records: Sequence[R], label_of: Callable[[R], str], a: str, b: str) -> dict[str, Any]:
    """Per-task and overall paired statistics of configuration ``a`` against ``b``.

    Only (task, seed) pairs both configurations ran are compared; the others are counted in
    ``unpaired``.  ``difference`` is success rate of ``a`` minus that of ``b`` on the pairs.
    """
    outcome: dict[str, dict[tuple[str, int], bool]] = {a: {}, b: {}}
    for r in records:
        lab = label_of(r)
        if lab in outcome:
            outcome[lab][(r.task, r.seed)] = r.success
    common = sorted(set(outcome[a]) & set(outcome[b]))
    unpaired = len(set(outcome[a]) ^ set(outcome[b]))
    by_task: dict[str, list[tuple[bool, bool]]] = {}
    for key in common:
        by_task.setdefault(key[0], []).append((outcome[a][key], outcome[b][key]))
    every = [(outcome[a][k], outcome[b][k]) for k in common]
    return {"a": a, "b": b, "alpha": ALPHA, "unpaired": unpaired,
            "tasks": {t: _cell(p) for t, p in sorted(by_task.items())}, "overall": _cell(every)}


def wilson(successes: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """The Wilson score interval of a binomial proportion (95 % by default); (0, 1) when n = 0."""
    if n <= 0:
        return 0.0, 1.0
    p = successes / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)
