"""Whether a reporter's verdict can be acted on: the structured verdict behind the ``careful`` loop.

A verdict is *high-confidence* when it is consistent in itself and with the scene:

* ``True`` naming no wrong object, or
* ``False`` naming at least one real object the robot can move (resolved by
  :func:`capmj.agents.report.scene_facts.resolve_name`).

Otherwise it is *low-confidence*, for one of the reasons of :data:`LOW_CONFIDENCE`: a "not
achieved" that cannot say which object is wrong gives a re-plan nothing to fix; naming only fixed
objects (zones, bowls: the robot cannot move them, so they are where they started) contradicts the
facts, and so does an "achieved" that lists wrong objects.  A ``direct`` verdict (asked as a plain
question after the model's checking code failed twice: the ``records`` prompt's fallback to the
``checked`` question) is low-confidence whatever it says.  So is a verdict the reporter itself
doubts (``Report.doubt``): a reason copying the prompt's own example
(:class:`~capmj.agents.report.checked.CheckedReporter`), a check that says "achieved" of the scene
the robot started from, where no task's goal holds
(:class:`~capmj.agents.report.goalcheck.GoalCheckReporter`), a check whose text cannot depend on the
scene (``blind_check``), and the ``relations`` gates' keys.  The ``careful`` loop
(:mod:`capmj.agents.llm_agent.loop_policy`) keeps the state instead of re-planning on a
low-confidence verdict; ``judge`` records the confidence of every verdict so its accuracy can be
measured apart.  Why each reason exists: ``docs/judge.md``, "Why each gate exists", and
``docs/llm.md`` (the loop policies).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from capmj.agents.report.scene_facts import resolve_name
from capmj.agents.report.verdict import Report
from capmj.sim.objects import ObjectSpec

__all__ = ["CONFIDENCE_LEVELS", "LOW_CONFIDENCE", "Assessment", "assess"]

CONFIDENCE_LEVELS = ("high", "low")
LOW_CONFIDENCE: dict[str, str] = {
    "no_verdict": "the reporter reached no verdict (unparseable or unknown)",
    "names_nothing": "not achieved, but no wrong object named",
    "names_no_real_object": "not achieved, but none of the names is an object of the scene",
    "names_only_fixed": "not achieved, but it names only objects the robot cannot move (they are where they started)",
    "achieved_but_names_wrong": "achieved, yet it names objects as wrong",
    "direct_fallback": "the verdict came from the direct question after the reporter's checks failed",
    "copies_example": "its reason is the prompt's own example, word for word",
    "holds_at_start": "its check also says the goal holds in the scene the robot started from",
    "blind_check": "its check reads no measured key, or compares one only with a value no record can have",
    "impossible_check": "its check asks for relations no scene can satisfy together (relations prompt)",
    "ungrounded_literal": "its check picks a block colour or a count the goal does not give (relations prompt)",
    "misses_a_relation": "its check never asks for a relation the goal names (relations prompt)",
}
"""Why a verdict is low-confidence (the key is recorded)."""


@dataclass(frozen=True)
class Assessment:
    """A verdict checked against the scene: its confidence and the real movable objects it names."""

    confidence: str
    """``"high"`` or ``"low"``."""
    why: str | None = None
    """A key of :data:`LOW_CONFIDENCE` when low, else None."""
    wrong_ids: tuple[int, ...] = ()
    """obj_ids of the movable objects the verdict names as wrong, in its order."""


def assess(report: Report | None, objects: Sequence[ObjectSpec]) -> Assessment:
    """The :class:`Assessment` of ``report`` (None: no reporter ran, low with ``no_verdict``)."""
    if report is None or report.verdict is None:
        return Assessment("low", "no_verdict")
    if report.source == "direct":
        return Assessment("low", "direct_fallback")
    if report.doubt is not None:
        return Assessment("low", report.doubt)
    named = [resolve_name(n, objects) for n in report.wrong]
    real = [o for o in named if o is not None]
    movable = tuple(dict.fromkeys(o.obj_id for o in real if not o.fixed))
    if report.verdict:
        return Assessment("low", "achieved_but_names_wrong", movable) if movable else Assessment("high")
    if not report.wrong:
        return Assessment("low", "names_nothing")
    if not real:
        return Assessment("low", "names_no_real_object")
    if not movable:
        return Assessment("low", "names_only_fixed")
    return Assessment("high", None, movable)
