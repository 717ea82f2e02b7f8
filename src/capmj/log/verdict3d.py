"""The verdict drawn in 3D: which objects fail the goal, why, and where the task wants them.

Tasks report failures as diagnostics, short sentences that name objects the way
:func:`capmj.tasks.predicates.short_label` does ("small red block 3 is not in the red bowl 1: ...").
A diagnostic's *subject* is the object it starts with; a diagnostic that starts otherwise ("2 of 3
blocks form a valid stack in the green zone 7") is about the whole task and has none.  Subjects
of a failed episode's diagnostics get an outline labelled with the diagnostic; every object a
diagnostic or an oracle goal names gets its name shown.  Where an object should be comes from the
task's oracle goals (the nearest target the object may go to), so no task has to say it twice.
"""

from __future__ import annotations

import re
import textwrap
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from capmj.log.paths import VERDICT, object_entity
from capmj.sim.pose import Vector

FAIL_COLOR = [255, 40, 40]
OK_COLOR = [60, 210, 90]
NEUTRAL_COLOR = [170, 170, 170]
TARGET_COLOR = [255, 160, 0]
LABEL_WIDTH = 48
"""Diagnostic labels in 3D are wrapped at this many characters."""
LABEL_LIFT = 0.06
"""Height (m) above a failing object's outline where its diagnostic is written."""
_NAME = re.compile(r"\b(block|zone|bowl|ball|fixture) (\d+)\b")
_SUBJECT_PREFIX = re.compile(r"^(?:the |a |an )?(?:[a-z]+ ){0,3}$")
"""What may precede a diagnostic's subject: an article and up to three words (size, colour)."""


def named_objects(text: str, kinds: Mapping[int, str]) -> list[int]:
    """Ids of the objects ``text`` names as ``<kind> <id>`` (in order, once each)."""
    out: list[int] = []
    for m in _NAME.finditer(text):
        i = int(m.group(2))
        if kinds.get(i) == m.group(1) and i not in out:
            out.append(i)
    return out


def subject(text: str, kinds: Mapping[int, str]) -> int | None:
    """The object a diagnostic is about: the one it starts with, else None."""
    for m in _NAME.finditer(text):
        i = int(m.group(2))
        if kinds.get(i) != m.group(1):
            continue
        return i if _SUBJECT_PREFIX.match(text[:m.start()].lower()) else None
    return None


@dataclass(frozen=True)
class VerdictView:
    """What the 3D verdict shows, derived from the diagnostics and the oracle goals."""

    success: bool
    failing: Mapping[int, tuple[str, ...]] = field(default_factory=dict)   # subject id -> its diagnostics
    named: tuple[int, ...] = ()                                           # ids whose names are shown
    in_goal: frozenset[int] = frozenset()

    def holds(self, obj_id: int | None) -> bool | None:
        """Whether the goal condition of ``obj_id`` holds at the end (None: the goal says nothing)."""
        if obj_id is None:
            return None
        if obj_id in self.failing:
            return False
        if obj_id in self.in_goal or self.success:
            return True
        return None


def verdict_view(success: bool, diagnostics: Sequence[str], kinds: Mapping[int, str],
                 goals: Sequence[Any] = ()) -> VerdictView:
    failing: dict[int, list[str]] = {}
    named: list[int] = []
    in_goal = frozenset(int(i) for g in goals for i in g.objects)
    for d in diagnostics:
        if not success:
            s = subject(d, kinds)
            if s is not None:
                failing.setdefault(s, []).append(d)
        named += [i for i in named_objects(d, kinds) if i not in named]
    named += sorted(i for i in in_goal if i not in named and i in kinds)
    return VerdictView(success, {k: tuple(v) for k, v in failing.items()}, tuple(named), in_goal)


def goal_target(obj_id: int, final_pos: Vector, goals: Sequence[Any]) -> np.ndarray | None:
    """Where the oracle goals want ``obj_id``: the nearest (in xy) target it may go to, or None."""
    best, best_d = None, np.inf
    p = np.asarray(final_pos, dtype=float)
    for g in goals:
        if obj_id not in g.objects:
            continue
        row = g.matches[list(g.objects).index(obj_id)]
        for j, ok in enumerate(row):
            if ok:
                t = np.asarray(g.targets[j].pos, dtype=float)
                d = float(np.hypot(*(t[:2] - p[:2])))
                if d < best_d:
                    best, best_d = t, d
    return best


def log_verdict(rr: Any, rec: Any, view: VerdictView, objects: Mapping[int, Any],
                final: Mapping[int, np.ndarray], goals: Sequence[Any]) -> int:
    """Outline + label the failing objects (static, following each object), show the names of the
    named objects, and (at the current time) arrows to where failing objects should be.  Returns
    the number of arrows drawn."""
    for i in view.named:
        o = objects[i]
        if i in view.failing:
            continue
        rec.log(object_entity(o.body) + "/name", rr.Points3D([[0, 0, o.half_extents[2] + 0.01]], radii=[0.001],
                                                             labels=[_label(o)]), static=True)
    origins, vectors, tboxes, tsizes, tlabels = [], [], [], [], []
    for i, diags in view.failing.items():
        o = objects[i]
        half = [h * 1.25 + 0.006 for h in o.half_extents]
        text = "\n".join(textwrap.fill(d, LABEL_WIDTH) for d in diags)
        rec.log(object_entity(o.body) + "/verdict",  # outline, and the diagnostic floating above it
                rr.Boxes3D(half_sizes=[half], colors=[FAIL_COLOR], radii=[0.003]),
                rr.Points3D([[0, 0, half[2] + LABEL_LIFT]], radii=[0.004], colors=[FAIL_COLOR], labels=[text]),
                static=True)
        if i in final:
            target = goal_target(i, final[i], goals)
            if target is not None and np.linalg.norm(target - final[i]) > 0.01:
                origins.append(final[i].tolist())
                vectors.append((target - final[i]).tolist())
                tboxes.append(target.tolist())
                tsizes.append(list(o.half_extents))
                tlabels.append(f"{o.kind} {i} goes here")
    if origins:
        rec.log(f"{VERDICT}/arrows", rr.Arrows3D(origins=origins, vectors=vectors, colors=[TARGET_COLOR],
                                                 radii=[0.004]))
        rec.log(f"{VERDICT}/targets", rr.Boxes3D(centers=tboxes, half_sizes=tsizes, colors=[TARGET_COLOR],
                                                 labels=tlabels, show_labels=False))  # names on hover
    return len(origins)


def _label(o: Any) -> str:
    from capmj.log.geometry import object_label

    return object_label(o)


__all__ = ["FAIL_COLOR", "NEUTRAL_COLOR", "OK_COLOR", "TARGET_COLOR", "VerdictView", "goal_target", "log_verdict",
           "named_objects", "subject", "verdict_view"]
