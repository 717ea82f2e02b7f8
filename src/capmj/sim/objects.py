"""Object specifications: what a scene contains, independent of MuJoCo.

A task's scene generator produces a tuple of :class:`ObjectSpec`; the world builder turns it into
MJCF.  Keeping specs as plain frozen data means the same specs always compile to the same model,
scenes can be hashed and compared in tests, and the planner-facing names are derived in exactly
one place.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal

from capmj.errors import ConfigError
from capmj.sim.palette import COLORS, COLOR_NAMES

Kind = Literal["block", "zone", "bowl", "ball", "fixture"]
KINDS: tuple[str, ...] = ("block", "zone", "bowl", "ball", "fixture")
FIXED_KINDS: frozenset[str] = frozenset({"zone", "bowl", "ball", "fixture"})

BLOCK_SIZES: dict[str, float] = {"tiny": 0.02, "small": 0.04, "big": 0.06}
"""Edge length (m) of the cube for each block size name."""
BLOCK_MASS: dict[str, float] = {"tiny": 0.01, "small": 0.05, "big": 0.1}

ZONE_SIZE = 0.12
ZONE_HEIGHT = 0.001
BOWL_RADIUS = 0.06          # outer radius of the rim
BOWL_INNER_RADIUS = 0.052   # free radius inside the wall
BOWL_HEIGHT = 0.035
BOWL_FLOOR = 0.004
BALL_RADIUS = 0.03
FIXTURE_WALL = 0.01         # wall thickness
FIXTURE_HEIGHT = 0.04
FIXTURE_LONG, FIXTURE_SHORT = 0.10, 0.05
FIXTURE_CLEARANCE = 0.003
"""Gap (m) between each wall's inner face and the footprint of a small block in its slots.  The
goal text of insert-blocks-in-fixture states exact slots; with walls touching those footprints a
block lowered at its slot scrapes a wall on the way down and pushes its neighbour out (0 of 5
exact-slot plans passed), with 3 mm every one lands (tests/test_outside_plans.py)."""


@dataclass(frozen=True)
class ObjectSpec:
    """One object of a scene.

    ``pos`` is the world position of the object's geometric centre (metres); ``yaw`` its rotation
    about +z (radians).  ``size`` names the block size and is ``None`` for other kinds; ``scale``
    multiplies a zone's footprint (Ravens "scaled" zones).
    """

    obj_id: int
    kind: Kind
    color: str
    pos: tuple[float, float, float]
    yaw: float = 0.0
    size: str | None = None
    scale: float = 1.0

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ConfigError(f"unknown object kind {self.kind!r}; valid kinds: {', '.join(KINDS)}")
        if self.color not in COLORS:
            raise ConfigError(f"unknown colour {self.color!r}; valid colours: {', '.join(COLOR_NAMES)}")
        if self.kind == "block" and self.size not in BLOCK_SIZES:
            raise ConfigError(f"block size must be one of {', '.join(BLOCK_SIZES)}, got {self.size!r}")
        if self.obj_id < 1:
            raise ConfigError(f"obj_id must be >= 1, got {self.obj_id}")

    @property
    def fixed(self) -> bool:
        """Fixed objects (zones, bowls, balls, fixtures) can never be picked."""
        return self.kind in FIXED_KINDS

    @property
    def body(self) -> str:
        """MuJoCo body name."""
        return f"obj{self.obj_id}"

    @property
    def name(self) -> str:
        """Planner-facing unique name, e.g. ``"movable small blue block with obj_id 3"``."""
        mobility = "fixed" if self.fixed else "movable"
        size = f"{self.size} " if self.size in ("big", "small", "tiny") else ""
        return f"{mobility} {size}{self.color} {self.kind} with obj_id {self.obj_id}"

    @property
    def half_extents(self) -> tuple[float, float, float]:
        """Half sizes of the object's local bounding box (x, y, z)."""
        if self.kind == "block":
            h = BLOCK_SIZES[self.size or "small"] / 2
            return (h, h, h)
        if self.kind == "zone":
            h = ZONE_SIZE * self.scale / 2
            return (h, h, ZONE_HEIGHT / 2)
        if self.kind == "bowl":
            return (BOWL_RADIUS, BOWL_RADIUS, BOWL_HEIGHT / 2)
        if self.kind == "ball":
            return (BALL_RADIUS, BALL_RADIUS, BALL_RADIUS)
        return (FIXTURE_LONG / 2, FIXTURE_LONG / 2, FIXTURE_HEIGHT / 2)

    @property
    def height(self) -> float:
        return 2 * self.half_extents[2]

    @property
    def footprint_radius(self) -> float:
        """Radius of a circle that contains the footprint at any yaw (for spawning)."""
        hx, hy, _ = self.half_extents
        return math.hypot(hx, hy)

    @property
    def xy_extent(self) -> tuple[float, float]:
        """Half sizes (m) of the axis-aligned xy box of the footprint at the object's own yaw
        (round objects: the radius).  Tighter than ``footprint_radius`` for large zones, whose
        circumscribed circle may not fit in the workspace although the square does."""
        hx, hy, _ = self.half_extents
        if self.kind in ("ball", "bowl"):
            return (hx, hy)
        c, s = abs(math.cos(self.yaw)), abs(math.sin(self.yaw))
        return (hx * c + hy * s, hx * s + hy * c)

    def moved(self, pos: tuple[float, float, float], yaw: float | None = None) -> "ObjectSpec":
        """A copy at another pose (used by scene generators while sampling)."""
        x, y, z = (float(v) for v in pos)
        return replace(self, pos=(x, y, z), yaw=self.yaw if yaw is None else float(yaw))


def resting_z(kind: str, size: str | None = None, scale: float = 1.0) -> float:
    """Centre height of an object of this kind resting on the table (z = 0)."""
    probe = ObjectSpec(1, kind, "red", (0.0, 0.0, 0.0), size=size, scale=scale)  # type: ignore[arg-type]
    return probe.half_extents[2]
