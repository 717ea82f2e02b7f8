"""Names and ids for detections, kept across re-perception: what the robot remembers.

Plans address objects by name ("movable small red block with obj_id 3"), so a perceived scene
must use exactly the names of :attr:`capmj.sim.objects.ObjectSpec.name`, and an object must keep
its id while it is moved.  :class:`Tracker` does that without any simulator state:

* the first perception numbers the detections 1, 2, ... in the perceiver's stable order;
* each later perception is matched one-to-one to what is remembered (Hungarian on 3-D distance,
  same kind and colour required), after moving each object the robot itself just moved to where
  it was put (the caller knows: it commanded the move), so a block keeps its id across a
  pick-and-place;
* a remembered block that is no longer seen, but lies under a block now seen (its footprint
  covers it, its top is no higher than that block's bottom), is *hidden in a tower*: it stays,
  at its remembered pose, marked not visible.  Top views cannot see it; memory can;
* a remembered *fixed* object (zone, bowl, ball, fixture: welded to the world, the robot never
  moves one) that is not seen whole, because something put on it cuts its top into pieces, is
  *covered*: it stays at its remembered pose under its id, and the unmatched new detections of
  its colour whose centres lie within its box are taken for its pieces, not new objects (a
  block dropped on a fixture's corner broke it into two balls and a block of its colour, and the
  plan's name for the fixture vanished);
* new detections get fresh ids above every id used so far; remembered objects neither seen nor
  hidden nor covered are dropped.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Mapping, Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from capmj.perception.detect import Detection

TRACK_GATE = 0.03
"""A remembered object and a detection farther apart than this (m) are different objects."""
_COVER_MARGIN = 0.01


def object_name(kind: str, color: str, size: str | None, obj_id: int) -> str:
    """The planner-facing name, in exactly the format of :attr:`capmj.sim.objects.ObjectSpec.name`."""
    mobility = "movable" if kind == "block" else "fixed"
    size_word = f"{size} " if size in ("big", "small", "tiny") else ""
    return f"{mobility} {size_word}{color} {kind} with obj_id {obj_id}"


@dataclass(frozen=True)
class Tracked:
    """One remembered object: its id, its latest detection, and whether it was seen last time."""

    obj_id: int
    detection: Detection
    visible: bool = True

    @property
    def name(self) -> str:
        d = self.detection
        return object_name(d.kind, d.color, d.size, self.obj_id)


def _moved(d: Detection, pos: Sequence[float]) -> Detection:
    """``d`` translated so that its centre is at ``pos`` (its box moves with it)."""
    shift = np.subtract(pos, d.position)
    lo, hi = np.add(d.aabb[0], shift), np.add(d.aabb[1], shift)
    box = (tuple(float(v) for v in lo), tuple(float(v) for v in hi))
    return replace(d, position=tuple(float(v) for v in pos), aabb=box)  # type: ignore[arg-type]


def _inside(d: Detection, box: tuple[tuple[float, float, float], tuple[float, float, float]]) -> bool:
    """Whether ``d``'s centre lies within ``box`` in xy."""
    (x0, y0, _), (x1, y1, _) = box
    return x0 <= d.position[0] <= x1 and y0 <= d.position[1] <= y1


def _pieces(fixed: Detection, detections: Sequence[Detection], free: set[int]) -> list[int]:
    """The unmatched detections (indices in ``free``) that are pieces of the remembered fixed
    object ``fixed``: its colour, centre within its box."""
    return [j for j in sorted(free) if detections[j].color == fixed.color and _inside(detections[j], fixed.aabb)]


def _covers(top: Detection, below: Detection) -> bool:
    """Whether ``top`` sits over ``below``: xy within its box (+1 cm), ``below``'s top under its bottom."""
    x, y, _ = below.position
    (x0, y0, z0), (x1, y1, _) = top.aabb
    inside = x0 - _COVER_MARGIN <= x <= x1 + _COVER_MARGIN and y0 - _COVER_MARGIN <= y <= y1 + _COVER_MARGIN
    return inside and below.aabb[1][2] <= z0 + 0.005


@dataclass(frozen=True)
class Tracker:
    """The remembered objects, in id order (immutable: :meth:`update` returns a new tracker)."""

    objects: tuple[Tracked, ...] = ()
    next_id: int = 1

    @classmethod
    def start(cls, detections: Sequence[Detection]) -> Tracker:
        return cls().update(detections)

    @property
    def names(self) -> list[str]:
        return [t.name for t in self.objects]

    def update(self, detections: Sequence[Detection], moved: Mapping[int, Sequence[float]] | None = None) -> Tracker:
        """The tracker after a new perception; ``moved`` maps the ids the robot moved since the last
        one to where it put them (centre, m)."""
        moved = moved or {}
        old = [replace(t, detection=_moved(t.detection, moved[t.obj_id])) if t.obj_id in moved else t
               for t in self.objects]
        pairs: dict[int, int] = {}  # detection index -> old index
        if old and detections:
            a = np.array([t.detection.position for t in old])
            b = np.array([d.position for d in detections])
            cost = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=-1)
            same = np.array([[t.detection.kind == d.kind and t.detection.color == d.color for d in detections]
                             for t in old])
            cost = np.where(same & (cost <= TRACK_GATE), cost, 1e3)
            for i, j in zip(*linear_sum_assignment(cost)):
                if cost[i, j] < 1e3:
                    pairs[int(j)] = int(i)
        seen_old = set(pairs.values())
        free = set(range(len(detections))) - set(pairs)
        covered: list[Tracked] = []
        for i, t in enumerate(old):
            if i not in seen_old and t.detection.fixed:
                pieces = _pieces(t.detection, detections, free)
                if pieces:
                    covered.append(Tracked(t.obj_id, t.detection, True))
                    free -= set(pieces)
        kept: list[Tracked] = list(covered)
        next_id = self.next_id
        for j, d in enumerate(detections):
            if j in pairs:
                kept.append(Tracked(old[pairs[j]].obj_id, d, True))
            elif j in free:
                kept.append(Tracked(next_id, d, True))
                next_id += 1
        for i, t in enumerate(old):
            if i not in seen_old and t.detection.kind == "block" and any(_covers(d, t.detection) for d in detections):
                kept.append(Tracked(t.obj_id, t.detection, False))
        return Tracker(tuple(sorted(kept, key=lambda t: t.obj_id)), next_id)

    def by_id(self, obj_id: int) -> Tracked:
        for t in self.objects:
            if t.obj_id == obj_id:
                return t
        raise KeyError(obj_id)


__all__ = ["TRACK_GATE", "Tracked", "Tracker", "object_name"]
