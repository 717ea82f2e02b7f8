"""Whether a reporter's verdict can be acted on: the structured verdict behind the ``careful`` loop.

A verdict is *high-confidence* when it is consistent in itself and with the scene: ``True`` naming
no wrong object, or ``False`` naming at least one real object the robot can move (resolved by
:func:`capmj.agents.report.scene.resolve_name`).  Otherwise it is *low-confidence*, for the first
of the :data:`RULES` that holds, or because a gate of its reporter kept it doubted
(:attr:`Report.doubt`, a :class:`~capmj.agents.report.verdict.Gate`'s key).  The reasons,
:func:`low_confidence_reasons` (also ``LOW_CONFIDENCE``), are derived from the rules and from the
gates of every reporter of :data:`capmj.agents.choices.REPORTER_TABLE`; none is listed by hand.

The ``careful`` loop (:mod:`capmj.agents.llm_agent.loop_policy`) keeps the state instead of
re-planning on a low-confidence verdict; ``judge`` records the confidence of every verdict so its
accuracy can be measured apart.  Why each reason exists: ``docs/judge.md``, "Why each gate exists".
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from capmj.agents.choices import REPORTER_TABLE
from capmj.agents.report.registry import load_reporter
from capmj.agents.report.scene import resolve_name
from capmj.agents.report.verdict import Report
from capmj.sim.objects import ObjectSpec

__all__ = ["CONFIDENCE_LEVELS", "RULES", "SCENE_RULES", "VERDICT_RULES", "Assessment", "Named", "Rule", "assess", "low_confidence_reasons"]

CONFIDENCE_LEVELS = ("high", "low")


@dataclass(frozen=True)
class Named:
    """What a verdict's ``wrong`` names in the scene."""

    real: tuple[ObjectSpec, ...]
    """The real objects it names."""
    movable: tuple[int, ...]
    """obj_ids of the movable ones among them, in its order."""


@dataclass(frozen=True)
class Rule:
    """A reason of the verdict itself to be low-confidence: its key, why, and its test."""

    key: str
    why: str
    test: Callable[[Report, Named], bool]


VERDICT_RULES: tuple[Rule, ...] = (
    Rule("no_verdict", "the reporter reached no verdict (unparseable or unknown)", lambda r, n: r.verdict is None),
    Rule("direct_fallback", "the verdict came from the direct question after the reporter's checks failed",
         lambda r, n: r.source == "direct"),
)
"""Tried first, before the reporter's own doubt (:attr:`Report.doubt`)."""
SCENE_RULES: tuple[Rule, ...] = (
    Rule("achieved_but_names_wrong", "achieved, yet it names objects as wrong", lambda r, n: bool(r.verdict and n.movable)),
    Rule("names_nothing", "not achieved, but no wrong object named", lambda r, n: not r.verdict and not r.wrong),
    Rule("names_no_real_object", "not achieved, but none of the names is an object of the scene",
         lambda r, n: not r.verdict and not n.real),
    Rule("names_only_fixed", "not achieved, but it names only objects the robot cannot move (they are where they "
                             "started)", lambda r, n: not r.verdict and not n.movable),
)
"""Tried after the reporter's own doubt, in order."""
RULES = VERDICT_RULES + SCENE_RULES


@functools.cache
def low_confidence_reasons() -> dict[str, str]:
    """Why a verdict is low-confidence, by the key that is recorded: the :data:`RULES` and the gates that
    keep a verdict doubted, of every reporter of the table (their modules imported now)."""
    reasons = {rule.key: rule.why for rule in RULES}
    for prompts in REPORTER_TABLE.values():
        for entry in prompts.values():
            reasons.update({gate.key: gate.why for gate in load_reporter(entry.target).gates if gate.keeps})
    return reasons


def __getattr__(name: str) -> dict[str, str]:
    if name == "LOW_CONFIDENCE":  # derived when first read: it imports every reporter
        return low_confidence_reasons()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class Assessment:
    """A verdict checked against the scene: its confidence and the real movable objects it names."""

    confidence: str
    """``"high"`` or ``"low"``."""
    why: str | None = None
    """A key of :func:`low_confidence_reasons` when low, else None."""
    wrong_ids: tuple[int, ...] = ()
    """obj_ids of the movable objects the verdict names as wrong, in its order."""


def assess(report: Report | None, objects: Sequence[ObjectSpec]) -> Assessment:
    """The :class:`Assessment` of ``report`` (None: no reporter ran, low with ``no_verdict``)."""
    if report is None:
        return Assessment("low", VERDICT_RULES[0].key)
    named = [resolve_name(n, objects) for n in report.wrong]
    real = tuple(o for o in named if o is not None)
    found = Named(real, tuple(dict.fromkeys(o.obj_id for o in real if not o.fixed)))
    for rule in VERDICT_RULES:
        if rule.test(report, found):
            return Assessment("low", rule.key)
    if report.doubt is not None:
        return Assessment("low", report.doubt)
    for rule in SCENE_RULES:
        if rule.test(report, found):
            return Assessment("low", rule.key, found.movable if report.verdict else ())
    return Assessment("high", None, found.movable)
