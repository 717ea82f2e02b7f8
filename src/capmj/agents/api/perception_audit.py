"""The perception error of an rgbd episode, scored against the truth for the record only.

Why in the agents layer and not in the perceiver: the perceiver must never see the truth (it
gets images and cameras, nothing else), but the benchmark must say what perception got wrong in
every episode and whether a miss was perception's fault.  :class:`PerceptionAudit` sits beside
the perceived planner API (:mod:`capmj.agents.api.perceived`), which hands it each new view of the
table *after* the view is made; it reads the world's true objects, matches them to the API's
objects (:func:`capmj.perception.score.score`) and writes a
:class:`~capmj.records.PerceptionNotes` into ``ctx.notes["perception"]``, which the runner puts
in the episode's result.  Nothing flows back into perception: the only thing the API takes from
the audit is whether a failed pick must be reported as :class:`~capmj.errors.PerceptionFailed`
rather than :class:`~capmj.errors.MotionFailed`, which changes the error's class, not its text.

When the episode's recorder draws perception (:class:`capmj.record.PerceptionViews`, the ``.rrd``
writer does), every view is also sent to it: the API's objects as boxes, each judged right, wrong
or false by the same matching, and the call's figures — so the log shows what the robot believed
beside the true objects, after every perception call.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Sequence

import numpy as np

from capmj.agents.base import EpisodeContext
from capmj.perception.detect import Detection
from capmj.perception.score import Score, TrueObject, score
from capmj.perception.track import Tracked, Tracker
from capmj.record import MatchStatus, PerceivedBox, PerceptionViews
from capmj.records import PerceptionCall, PerceptionNotes
from capmj.records.perception import POSITION_TOL_MM, SLOT_TOL_MM

__all__ = ["NOTES_KEY", "PerceptionAudit", "footprint_box", "perceived_boxes", "true_objects"]

_SQUARES = ("block", "zone")
"""Kinds whose detections are squares with a yaw; the others are drawn as their axis-aligned box."""

NOTES_KEY = "perception"
"""The key of ``ctx.notes`` that holds the episode's :class:`PerceptionNotes`."""


def true_objects(world: Any) -> tuple[list[int], list[TrueObject]]:
    """The world's objects as the truth scoring takes them (poses now), with their obj_ids."""
    ids, out = [], []
    for o in world.objects:
        pose = world.pose(o.obj_id)
        ids.append(o.obj_id)
        x, y, z = (float(v) for v in pose.pos)
        out.append(TrueObject(o.kind, o.color, o.size, (x, y, z), float(pose.yaw)))
    return ids, out


def _call(attempt: int, stage: str, figures: dict[str, Any]) -> PerceptionCall:
    return PerceptionCall(
        attempt=attempt, stage=stage, objects=figures["n_true"], detections=figures["n_detected"],
        missed=figures["n_true"] - figures["matched"], false_detections=figures["n_detected"] - figures["matched"],
        kind_errors=figures["kind_errors"], color_errors=figures["color_errors"], size_errors=figures["size_errors"],
        median_pos_mm=_mm(figures["median_pos_mm"]), max_pos_mm=_mm(figures["max_pos_mm"]),
        max_yaw_deg=_mm(figures["max_yaw_deg"]), max_slot_mm=_mm(figures["max_slot_mm"]))


def _mm(v: float | None) -> float | None:
    return None if v is None else round(float(v), 3)


def footprint_box(d: Detection) -> tuple[tuple[float, float, float], tuple[float, float, float], float]:
    """Centre, half size and yaw of the box drawn for ``d``: a square's side recovered from its
    axis-aligned box and yaw (the box of a square of half side h turned by yaw has half width
    h (|cos yaw| + |sin yaw|)), any other kind's axis-aligned box itself."""
    lo, hi = np.asarray(d.aabb[0], float), np.asarray(d.aabb[1], float)
    centre = tuple(float(v) for v in (lo + hi) / 2)
    half = (hi - lo) / 2
    yaw = float(d.yaw) if d.kind in _SQUARES else 0.0
    if d.kind in _SQUARES:
        side = float(half[:2].mean()) / (abs(math.cos(yaw)) + abs(math.sin(yaw)))
        half[:2] = side
    return centre, tuple(float(v) for v in half), yaw  # type: ignore[return-value]


def perceived_boxes(tracked: Sequence[Tracked], s: Score, true_ids: Sequence[int]) -> tuple[PerceivedBox, ...]:
    """The tracked objects as boxes, each judged by its match in ``s`` (see :data:`MatchStatus`)."""
    by_det = {m.detection: m for m in s.matches}
    out = []
    for j, t in enumerate(tracked):
        m = by_det.get(j)
        status: MatchStatus = "false"
        if m is not None:
            right = (m.kind_ok and m.color_ok and m.size_ok and 1000 * m.position_error <= POSITION_TOL_MM
                     and (m.slot_error is None or 1000 * m.slot_error <= SLOT_TOL_MM))
            status = "right" if right else "wrong"
        centre, half, yaw = footprint_box(t.detection)
        out.append(PerceivedBox(t.obj_id, t.name, centre, half, yaw, float(t.detection.confidence), t.visible,
                                status, None if m is None else int(true_ids[m.truth])))
    return tuple(out)


class PerceptionAudit:
    """Scores one attempt's perceived views against the world (see the module docstring)."""

    def __init__(self, ctx: EpisodeContext, perceiver: str) -> None:
        self._ctx = ctx
        self._perceiver = perceiver
        self._moves = 0
        self._truth_of: dict[int, int] = {}
        """Perceived obj_id -> the true obj_id it was matched to in the latest view."""
        self._true_xy: dict[int, tuple[float, float]] = {}

    def observe(self, tracker: Tracker) -> None:
        """Score the planner API's objects after a perception call and record the figures."""
        ids, truth = true_objects(self._ctx.world)
        tracked = tracker.objects
        s = score([t.detection for t in tracked], truth)
        self._truth_of = {tracked[m.detection].obj_id: ids[m.truth] for m in s.matches}
        self._true_xy = {oid: (t.position[0], t.position[1]) for oid, t in zip(ids, truth)}
        stage = "reset" if self._moves == 0 else f"move {self._moves}"
        call = _call(self._ctx.attempt + 1, stage, s.to_dict())
        notes = self._notes()
        self._ctx.notes[NOTES_KEY] = replace(notes, calls=(*notes.calls, call))
        recorder = self._ctx.recorder
        if isinstance(recorder, PerceptionViews):
            recorder.perception(float(self._ctx.world.time), call, perceived_boxes(tracked, s, ids))

    def pick_missed(self, held: int | None, pick: Sequence[float] | np.ndarray, gripped_true: int | None) -> bool:
        """Whether a pick missed because of perception: the plan meant perceived object ``held``,
        the primitive did not grip that object (``gripped_true``: the true obj_id it gripped, None
        for nothing), and the pick point ``pick`` lay off it (farther than the tolerance from its
        true centre in xy) — or ``held`` matches no true object and nothing was gripped.  Recorded
        in the notes when it did."""
        self._moves += 1
        if held is None:
            return False  # a pick at a bare position: the plan chose the point, not perception
        target = self._truth_of.get(held)
        if gripped_true == target if target is not None else gripped_true is not None:
            return False  # it gripped the object meant (or, meaning one not there, gripped a real one)
        xy = self._true_xy.get(target) if target is not None else None
        off = xy is None or 1000 * math.dist((float(pick[0]), float(pick[1])), xy) > POSITION_TOL_MM
        if off:
            notes = self._notes()
            self._ctx.notes[NOTES_KEY] = replace(notes, pick_misses=(*notes.pick_misses, self._ctx.attempt + 1))
        return off

    def _notes(self) -> PerceptionNotes:
        notes = self._ctx.notes.get(NOTES_KEY)
        return notes if isinstance(notes, PerceptionNotes) else PerceptionNotes(self._perceiver)

