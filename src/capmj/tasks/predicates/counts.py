"""Counting goals: how many blocks of which colour a zone holds, how many a group or a zone
must hold (the arithmetic of the divide-blocks and max-odd-number goals; public because generated
tasks may state the same goals)."""

from __future__ import annotations

from capmj.sim.state import SceneState
from capmj.tasks.predicates.containment import objects_in_zone


def largest_odd_at_most(n: int) -> int:
    """The largest odd number ≤ ``n`` (0 when ``n`` < 1)."""
    return n if n % 2 == 1 else max(n - 1, 0)


def zone_color_counts(state: SceneState, zone_id: int) -> dict[str, list[int]]:
    """``{colour: [block ids]}`` of the blocks whose centre is in the zone (see :func:`in_zone`)."""
    out: dict[str, list[int]] = {}
    for i in objects_in_zone(state, zone_id):
        out.setdefault(state.spec(i).color, []).append(i)
    return out


def group_sizes(n: int, k: int) -> list[int]:
    """Sizes of ``n`` items divided into groups of ``k`` (the last one smaller when k ∤ n),
    largest first."""
    return [k] * (n // k) + ([n % k] if n % k else [])


__all__ = ["group_sizes", "largest_odd_at_most", "zone_color_counts"]
