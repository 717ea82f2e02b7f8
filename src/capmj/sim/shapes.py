"""Object shapes in their own frames, as constants: no MuJoCo, no pose, no world.

The L-fixture's walls are needed by two layers that must not share more than this: the footprint
model (:mod:`capmj.sim.footprint`, which rotates shapes with :mod:`capmj.sim.pose` and so loads
MuJoCo) and the perceiver (:mod:`capmj.perception`, which sees only camera images and imports no
simulator).  Both read the walls from here, so there is one definition of where the walls stand,
which ``mjcf/fixture.xml`` builds (``tests/test_mjcf.py``, ``tests/test_footprint.py`` and
``tests/test_perception.py`` compare it with the file).
"""

from __future__ import annotations

from dataclasses import dataclass

from capmj.sim.objects import BLOCK_SIZES, FIXTURE_CLEARANCE, FIXTURE_HEIGHT, FIXTURE_LONG, FIXTURE_SHORT, FIXTURE_WALL


@dataclass(frozen=True, slots=True)
class LocalBox:
    """A box in an object's own frame: centre and half sizes (m), axes along the object's."""

    centre: tuple[float, float, float]
    half: tuple[float, float, float]


FIXTURE_SLOT = BLOCK_SIZES["small"]
"""Slot pitch ``a`` (m) of an L-fixture: its slots hold small blocks, and its body origin is the
centre of slot (0, 0)."""
FIXTURE_SLOTS_LOCAL: tuple[tuple[float, float, float], ...] = (
    (0.0, 0.0, 0.0), (FIXTURE_SLOT, 0.0, 0.0), (0.0, FIXTURE_SLOT, 0.0))
"""The three slots in the fixture frame (spec task 10): along the long wall, then the short one.
Here, beside the walls, because the task predicates and the perception audit both place them."""
_INNER = FIXTURE_SLOT / 2 + FIXTURE_CLEARANCE  # slot (0, 0) centre to a wall's inner face
FIXTURE_WALLS: tuple[LocalBox, ...] = (
    LocalBox((FIXTURE_LONG / 2 - _INNER - FIXTURE_WALL, -(_INNER + FIXTURE_WALL / 2), 0.0),
             (FIXTURE_LONG / 2, FIXTURE_WALL / 2, FIXTURE_HEIGHT / 2)),
    LocalBox((-(_INNER + FIXTURE_WALL / 2), FIXTURE_SHORT / 2 - _INNER, 0.0),
             (FIXTURE_WALL / 2, FIXTURE_SHORT / 2, FIXTURE_HEIGHT / 2)),
)
"""The L-fixture's walls in its frame (origin = slot (0, 0), a small block's centre): the long one
along the slot row's −y side, the short one along its −x side, both inner faces
``FIXTURE_CLEARANCE`` clear of the slots' footprints and both outer ends flush at the corner.
``mjcf/fixture.xml`` builds exactly these (geoms g0, g1)."""

FIXTURE_ORIGIN_IN = FIXTURE_WALL + FIXTURE_CLEARANCE + FIXTURE_SLOT / 2  # = _INNER + FIXTURE_WALL
"""How far (m) the origin (slot (0, 0)) lies in from the L's outer corner along each wall: a wall,
the clearance and half a small block (3.3 cm)."""
FIXTURE_RECT = (FIXTURE_LONG, FIXTURE_SHORT + FIXTURE_WALL)
"""Sides (m) of the rectangle enclosing the L seen from above: 10 x 6 cm."""

__all__ = ["FIXTURE_ORIGIN_IN", "FIXTURE_RECT", "FIXTURE_SLOT", "FIXTURE_SLOTS_LOCAL", "FIXTURE_WALLS", "LocalBox"]
