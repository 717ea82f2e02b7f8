"""What perception got wrong in one episode (``perception`` of a result; rgbd mode only).

Why a record: in ``--perception rgbd`` an episode's outcome depends on what the cameras made of
the table, so the perception error is a result like success, not a debugging aid.  The planner
API's view (the tracked detections, :class:`capmj.perception.track.Tracker`) is scored against
the truth after every perception call by :mod:`capmj.agents.api.perception_audit` — the truth is
read for this record only and never reaches the perceiver — and the figures land here, one
:class:`PerceptionCall` per call.  Failure attribution (:mod:`capmj.bench.failures`) reads
:meth:`PerceptionNotes.erred`; the summary (:mod:`capmj.bench.results`)
pools the calls per task.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from capmj.records.codec import from_plain, to_plain

__all__ = ["POSITION_TOL_MM", "SLOT_TOL_MM", "PerceptionCall", "PerceptionNotes"]

POSITION_TOL_MM = 10.0
"""A perceived centre farther than this from the true one is an error that can fail an episode:
the suction cup lands off a tiny block's 2 cm top and places land a centimetre off their slot.
The built-in perceiver's worst error at reset over 20 tasks x 20 seeds is 2.8 mm
(``benchmarks/results/perception.json``)."""

SLOT_TOL_MM = 3.0
"""A fixture whose perceived pose puts one of its slot centres farther than this from the true one
is an error that can fail an episode: it is the walls' clearance around a block lowered exactly at
its slot (``capmj.sim.objects.FIXTURE_CLEARANCE``, whose docstring says what a block lowered
off it does; records sit below ``sim``, so ``tests/test_perception_slots.py`` holds the two
equal).  A yaw error alone can do it: 2 a sin(err / 2) at pitch a = 4 cm is 3.5 mm at 5°, while
the fixture's reported position (slot (0, 0, 0)) stays within :data:`POSITION_TOL_MM`."""


@dataclass(frozen=True)
class PerceptionCall:
    """One perception call: the planner API's objects matched to the true ones
    (:func:`capmj.perception.score.score`).  ``stage`` is ``reset`` or ``move N`` (after the N-th
    pick-and-place of the attempt); errors in millimetres and degrees, None without a match.
    ``max_slot_mm`` is the worst slot-centre error of the matched fixtures
    (:func:`capmj.perception.score.slot_error`), None without one; lines written before it was
    recorded read as None (not measured), so their ``erred`` is what it was when they were labelled."""

    DEFAULT_IF_MISSING: ClassVar[frozenset[str]] = frozenset({"max_slot_mm"})

    attempt: int
    stage: str
    objects: int
    detections: int
    missed: int
    false_detections: int
    kind_errors: int = 0
    color_errors: int = 0
    size_errors: int = 0
    median_pos_mm: float | None = None
    max_pos_mm: float | None = None
    max_yaw_deg: float | None = None
    max_slot_mm: float | None = None

    @property
    def erred(self) -> bool:
        """Whether this call got an object wrong enough to fail a plan acting on it: a missed or
        false object, a wrong kind / colour / size, a centre more than :data:`POSITION_TOL_MM`
        off, or a fixture slot more than :data:`SLOT_TOL_MM` off."""
        wrong = self.missed + self.false_detections + self.kind_errors + self.color_errors + self.size_errors
        return (wrong > 0 or (self.max_pos_mm is not None and self.max_pos_mm > POSITION_TOL_MM)
                or (self.max_slot_mm is not None and self.max_slot_mm > SLOT_TOL_MM))

    def to_dict(self) -> dict[str, Any]:
        return to_plain(self)

    @classmethod
    def from_dict(cls, data: Any, *, strict: bool = True) -> "PerceptionCall":
        return from_plain(cls, data, strict=strict)


@dataclass(frozen=True)
class PerceptionNotes:
    """The perception of one episode: which perceiver, every call scored, and the attempt of each
    pick whose perceived point was off the object the plan meant (farther than
    :data:`POSITION_TOL_MM` from its true centre in xy, or at an object that is not there)."""

    perceiver: str
    calls: tuple[PerceptionCall, ...] = ()
    pick_misses: tuple[int, ...] = ()

    def acted_on(self, attempt: int) -> tuple[PerceptionCall, ...]:
        """The calls of ``attempt`` the robot acted on: each but the last was followed by a
        pick-and-place (every one triggers a new call); the last only shaped answers after the
        final move, unless it is the attempt's only call (the plan decided from it alone)."""
        mine = tuple(c for c in self.calls if c.attempt == attempt)
        return mine if len(mine) <= 1 else mine[:-1]

    def erred(self, attempt: int) -> bool:
        """Whether ``attempt`` picked off target or acted on a call that got an object wrong."""
        return attempt in self.pick_misses or any(c.erred for c in self.acted_on(attempt))

    @property
    def at_reset(self) -> PerceptionCall | None:
        """The first call of the episode (the scene as the episode starts)."""
        return self.calls[0] if self.calls else None

    def to_dict(self) -> dict[str, Any]:
        return to_plain(self)

    @classmethod
    def from_dict(cls, data: Any, *, strict: bool = True) -> "PerceptionNotes":
        return from_plain(cls, data, strict=strict)
