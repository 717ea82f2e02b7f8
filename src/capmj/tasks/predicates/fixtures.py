"""L-fixtures: where their three slots are, and which block fills each (spec task 10)."""

from __future__ import annotations

import math
from typing import Iterable

import numpy as np

from capmj.sim.shapes import FIXTURE_SLOT, FIXTURE_SLOTS_LOCAL
from capmj.sim.objects import FIXTURE_HEIGHT, FIXTURE_LONG, FIXTURE_WALL
from capmj.sim.pose import Vector, from_frame_2d
from capmj.sim.state import SceneState
from capmj.tasks.predicates.stacks import toppled

FIXTURE_RADIUS = math.hypot(FIXTURE_LONG - FIXTURE_SLOT / 2 - FIXTURE_WALL, FIXTURE_SLOT / 2 + FIXTURE_WALL)
"""Distance (m) from the fixture origin bounding its farthest point (the outer end of the long wall,
local (0.067, −0.033) with the walls ``FIXTURE_CLEARANCE`` out; the bound is that of walls
touching the slots, kept so scenes stay as they were); larger than ``ObjectSpec.footprint_radius``,
which assumes a centred box."""
SLOT_TOL = 0.012
"""A block fills a slot when its centre is within this distance (m, 3-D) of the slot centre."""


def fixture_slots(origin: Vector, yaw: float) -> np.ndarray:
    """(3, 3) world centres of a small block in each slot of an L-fixture whose origin (slot
    (0, 0), as ``get_obj_pos`` reports it) is ``origin`` and whose yaw is ``yaw``.

    The slot z is the table (``origin`` z − FIXTURE_HEIGHT/2) plus half a block.  The walls keep
    ``capmj.sim.objects.FIXTURE_CLEARANCE`` from these footprints, so a block lowered exactly
    here does not scrape them.
    """
    o = np.asarray(origin, dtype=float)
    z = float(o[2]) - FIXTURE_HEIGHT / 2 + FIXTURE_SLOT / 2
    xy = from_frame_2d([(u, v) for u, v, _ in FIXTURE_SLOTS_LOCAL], yaw, o[:2])
    return np.column_stack([xy, np.full(len(xy), z)])


def slot_occupants(state: SceneState, fixture_id: int, ids: Iterable[int], tol: float = SLOT_TOL) -> list[int | None]:
    """Per slot of the fixture, the upright block of ``ids`` whose centre is within ``tol``
    (0.012 m, 3-D) of the slot centre (the nearest one), else None."""
    slots = fixture_slots(state.pos(fixture_id), state.poses[fixture_id].yaw)
    out: list[int | None] = []
    for s in slots:
        best = min(((float(np.linalg.norm(state.pos(i) - s)), i) for i in ids if not toppled(state, i)), default=None)
        out.append(best[1] if best is not None and best[0] <= tol else None)
    return out


__all__ = ["FIXTURE_RADIUS", "FIXTURE_SLOT", "FIXTURE_SLOTS_LOCAL", "SLOT_TOL", "fixture_slots", "slot_occupants"]
