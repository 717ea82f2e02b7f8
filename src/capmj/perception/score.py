"""Scoring detections against the truth: one-to-one matching and the errors of each match.

The perceiver never sees the truth; benchmarks and tests hand it to :func:`score` as plain
:class:`TrueObject` records, so this module needs no world either.  Detections and true objects
are matched one-to-one (the Hungarian algorithm, :func:`scipy.optimize.linear_sum_assignment`), a
pair counting only within :data:`GATE` of 3-D distance between centres: a detection farther than
that from every object is a false positive, whatever its label, and an object with none that
close is missed.  Among the assignments within the gate, the matching takes, in this order, the
most pairs, then the fewest pairs of different kinds, then the least total distance (each step's
cost outweighs every sum of the next's).  Why kinds before distance: a fixture's reported
position is its slot (0, 0, 0), so a block inserted there stands within the gate of the
fixture's centre, and distance alone paired the two crosswise, scoring two kind / colour / size
errors for two objects that were both seen.  The distance is 3-D so that a block standing at a
zone's centre, or on another block, is matched to itself and not to what lies under it.  Kind,
colour and size are then compared on the matches only, so a confusion never hides as a miss.

Yaw errors respect symmetry: a square (block, zone) repeats every 90°, a fixture every 360°,
and round objects (bowls, balls) have no yaw and no yaw error.

A kind with slots (:data:`SLOTS`: the L-fixture's three) also gets a *slot error*: the largest
distance in xy between a slot centre placed by the perceived pose (position and yaw) and the same
slot placed by the true pose.  Why not the position and yaw errors alone: a plan puts blocks at
the slots, and a yaw error moves the far slots by its arc (2 a sin(err / 2) at pitch a: 3.5 mm at
5°), which matters against the walls' 3 mm clearance although the reported position (slot
(0, 0, 0)) is right.  xy only: a block is lowered into its slot, so a height error does not move
it towards a wall.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from capmj.perception.detect import Detection
from capmj.sim.shapes import FIXTURE_SLOTS_LOCAL

GATE = 0.02
"""Largest distance (m) between centres at which a detection can be an object's."""
_PERIOD = {"block": math.pi / 2, "zone": math.pi / 2, "fixture": 2 * math.pi}
SLOTS: dict[str, tuple[tuple[float, float, float], ...]] = {"fixture": FIXTURE_SLOTS_LOCAL}
"""The slots (object frame, m) of each kind that holds blocks in slots; another fixture kind is
one entry here."""


@dataclass(frozen=True)
class TrueObject:
    """What the truth says of one object (from a world, a snapshot or a test)."""

    kind: str
    color: str
    size: str | None
    position: tuple[float, float, float]
    yaw: float


@dataclass(frozen=True)
class Match:
    truth: int
    detection: int
    position_error: float
    """Euclidean (m), 3-D."""
    xy_error: float
    yaw_error: float | None
    """Radians, modulo the kind's symmetry; None for round kinds."""
    kind_ok: bool
    color_ok: bool
    size_ok: bool
    slot_error: float | None = None
    """Metres, xy: the worst slot centre of the perceived pose against the true one
    (:func:`slot_error`); None for kinds without slots."""


def yaw_error(kind: str, a: float, b: float) -> float | None:
    """|a - b| modulo the symmetry of ``kind`` (None when it has no yaw)."""
    period = _PERIOD.get(kind)
    if period is None:
        return None
    return abs(math.remainder(a - b, period))


def slot_error(kind: str, perceived: Sequence[float], perceived_yaw: float,
               true: Sequence[float], true_yaw: float) -> float | None:
    """Largest xy distance (m) between a slot of ``kind`` placed at the perceived pose and the
    same slot at the true pose (positions are the object's origin, as ``get_obj_pos`` reports
    it); None when ``kind`` has no slots."""
    slots = SLOTS.get(kind)
    if slots is None:
        return None
    local = np.array([(u, v) for u, v, _ in slots], dtype=float)

    def placed(origin: Sequence[float], yaw: float) -> np.ndarray:
        c, s = math.cos(yaw), math.sin(yaw)
        return np.asarray(origin[:2], dtype=float) + local @ np.array([[c, s], [-s, c]])

    return float(np.linalg.norm(placed(perceived, perceived_yaw) - placed(true, true_yaw), axis=1).max())


@dataclass(frozen=True)
class Score:
    """The matches of one perception call against its truth."""

    n_true: int
    n_detected: int
    matches: tuple[Match, ...]
    confusions: tuple[tuple[str, str], ...]
    """(true colour, perceived colour) of every match whose colour is wrong."""

    @property
    def recall(self) -> float:
        return len(self.matches) / self.n_true if self.n_true else 1.0

    @property
    def precision(self) -> float:
        return len(self.matches) / self.n_detected if self.n_detected else 1.0

    def to_dict(self) -> dict:
        """JSON-friendly figures of this call (errors in mm and degrees)."""
        pos = [m.position_error * 1000 for m in self.matches]
        yaw = [math.degrees(m.yaw_error) for m in self.matches if m.yaw_error is not None]
        slot = [m.slot_error * 1000 for m in self.matches if m.slot_error is not None]
        return {"n_true": self.n_true, "n_detected": self.n_detected, "matched": len(self.matches),
                "recall": self.recall, "precision": self.precision,
                "kind_errors": sum(not m.kind_ok for m in self.matches),
                "color_errors": sum(not m.color_ok for m in self.matches),
                "size_errors": sum(not m.size_ok for m in self.matches),
                "median_pos_mm": float(np.median(pos)) if pos else None,
                "max_pos_mm": max(pos) if pos else None,
                "max_yaw_deg": max(yaw) if yaw else None,
                "max_slot_mm": max(slot) if slot else None,
                "confusions": [list(c) for c in self.confusions]}


def score(detections: Sequence[Detection], truths: Sequence[TrueObject], gate: float = GATE) -> Score:
    """Match ``detections`` to ``truths`` one-to-one (see the module docstring)."""
    matches: list[Match] = []
    if detections and truths:
        d = np.array([det.position for det in detections])
        t = np.array([tr.position for tr in truths])
        dist = np.linalg.norm(t[:, None, :] - d[None, :, :], axis=-1)
        other_kind = np.array([[tr.kind != det.kind for det in detections] for tr in truths])
        pairs = min(len(truths), len(detections))
        kind_cost = (pairs + 1) * gate  # more than any sum of in-gate distances
        no_pair = (pairs + 1) * (kind_cost + gate)  # more than any sum of in-gate pair costs
        cost = np.where(dist <= gate, dist + kind_cost * other_kind, no_pair)
        rows, cols = linear_sum_assignment(cost)
        for i, j in zip(rows, cols):
            if dist[i, j] > gate:
                continue
            tr, det = truths[i], detections[j]
            same = det.kind == tr.kind
            matches.append(Match(
                truth=int(i), detection=int(j),
                position_error=float(np.linalg.norm(np.subtract(det.position, tr.position))),
                xy_error=float(np.linalg.norm(t[i, :2] - d[j, :2])),
                yaw_error=yaw_error(tr.kind, det.yaw, tr.yaw) if same else None,
                kind_ok=same, color_ok=det.color == tr.color, size_ok=det.size == tr.size,
                slot_error=slot_error(tr.kind, det.position, det.yaw, tr.position, tr.yaw) if same else None))
    confusions = tuple((truths[m.truth].color, detections[m.detection].color) for m in matches if not m.color_ok)
    return Score(len(truths), len(detections), tuple(matches), confusions)


__all__ = ["GATE", "SLOTS", "Match", "Score", "TrueObject", "score", "slot_error", "yaw_error"]
