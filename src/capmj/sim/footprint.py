"""What an object covers of the table seen from above: the one footprint model of capmj.

A footprint is a function of an object's spec and pose only (no MuJoCo model), so the planner API
(:mod:`capmj.agents.footprints`, live world poses or perceived ones) and the success predicates
(:mod:`capmj.tasks.predicates`, a settled :class:`~capmj.sim.state.SceneState`) measure the same
table.  Before this module they measured three different ones: the planner read its geoms' boxes
and switched to a world box beyond 20° of tilt, the judge rebuilt centred boxes from the half
extents beyond 15°, and the fixture's walls had a third copy in the perceived API.

The model: bowls and balls are discs (their outline whatever their yaw); blocks, zones and each
wall of a fixture are rectangles in the object's frame (:func:`local_boxes`), turned by its yaw;
an object tilted more than :data:`TILT_TOL` covers the world xy box of those boxes instead.

The arm's motion does not use this: it plans descents and transits on coarse axis-aligned world
boxes (:meth:`capmj.sim.primitives.Primitives.coarse_top_under`), where an overestimate is safe.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from capmj.sim.objects import (
    BALL_RADIUS,
    BLOCK_SIZES,
    BOWL_RADIUS,
    FIXTURE_CLEARANCE,
    FIXTURE_HEIGHT,
    FIXTURE_LONG,
    FIXTURE_SHORT,
    FIXTURE_WALL,
    ObjectSpec,
)
from capmj.sim.pose import from_frame_2d
from capmj.sim.state import Pose

TILT_TOL = math.radians(15.0)
"""Tilt (rad) beyond which an object no longer rests on a face: it is toppled.  The value is the
spec's ("a stack: … none tilted more than 15°") and the originals' SE(2) rotation tolerance.  The
footprint model uses the same limit: beyond it the faces no longer lie flat, so the face
rectangle understates the cover (a small block at 15° already reaches 4.5 mm past its face) and
the world xy box is used.  One limit, so an object the judge calls toppled is never one the
planner still measures as upright."""

ROUND_KINDS = frozenset({"bowl", "ball"})
"""Kinds whose footprint is a disc whatever their yaw (their geoms' boxes turn with it)."""

DISC_RADIUS: dict[str, float] = {"bowl": BOWL_RADIUS, "ball": BALL_RADIUS}
"""Footprint radius (m) of each round kind: the bowl's rim, the ball's equator."""


@dataclass(frozen=True, slots=True)
class Disc:
    """A round footprint part: centre (m) and radius (m)."""

    cx: float
    cy: float
    r: float


@dataclass(frozen=True, slots=True)
class Rect:
    """A rectangular footprint part: centre (m), yaw (rad) and half sizes along its own axes (m)."""

    cx: float
    cy: float
    yaw: float
    hx: float
    hy: float


Part = Disc | Rect
"""One footprint part."""


@dataclass(frozen=True, slots=True)
class LocalBox:
    """A box in an object's own frame: centre and half sizes (m), axes along the object's."""

    centre: tuple[float, float, float]
    half: tuple[float, float, float]


FIXTURE_SLOT = BLOCK_SIZES["small"]
"""Slot pitch ``a`` (m) of an L-fixture: its slots hold small blocks, and its body origin is the
centre of slot (0, 0)."""
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
``mjcf/fixture.xml`` builds exactly these (``tests/test_mjcf.py`` compares them)."""


def local_boxes(spec: ObjectSpec) -> tuple[LocalBox, ...]:
    """The boxes an object is made of, in its own frame: a fixture's two walls, else one box of
    the spec's half extents at the centre."""
    if spec.kind == "fixture":
        return FIXTURE_WALLS
    return (LocalBox((0.0, 0.0, 0.0), spec.half_extents),)


def world_box(spec: ObjectSpec, pose: Pose) -> tuple[np.ndarray, np.ndarray]:
    """World axis-aligned box (min corner, max corner) of the object's :func:`local_boxes` at
    ``pose`` (any orientation)."""
    rot = pose.rotation
    p = np.asarray(pose.pos, dtype=float)
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for b in local_boxes(spec):
        c = p + rot @ np.asarray(b.centre, dtype=float) if any(b.centre) else p
        ext = np.abs(rot) @ np.asarray(b.half, dtype=float)
        lo, hi = np.minimum(lo, c - ext), np.maximum(hi, c + ext)
    return lo, hi


def parts(spec: ObjectSpec, pose: Pose) -> list[Part]:
    """The footprint of an object at ``pose`` as discs and rectangles (see the module docstring)."""
    x, y = float(pose.pos[0]), float(pose.pos[1])
    if spec.kind in ROUND_KINDS:
        return [Disc(x, y, DISC_RADIUS[spec.kind])]
    if pose.tilt > TILT_TOL:
        lo, hi = world_box(spec, pose)
        return [Rect((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, 0.0, (hi[0] - lo[0]) / 2, (hi[1] - lo[1]) / 2)]
    yaw = pose.yaw
    out: list[Part] = []
    for b in local_boxes(spec):
        cx, cy = (x, y) if not any(b.centre) else (float(v) for v in from_frame_2d(b.centre[:2], yaw, (x, y)))
        out.append(Rect(cx, cy, yaw, b.half[0], b.half[1]))
    return out


def part_shape(part: Part):
    """One part as a shapely polygon (a disc: 32 segments per quarter circle)."""
    from shapely.geometry import Point, Polygon

    if isinstance(part, Disc):
        return Point(part.cx, part.cy).buffer(part.r, 32)
    hx, hy = part.hx, part.hy
    return Polygon(from_frame_2d([(hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)], part.yaw, (part.cx, part.cy)))


def shape(spec: ObjectSpec, pose: Pose):
    """The footprint of an object at ``pose`` as one shapely geometry (the union of its parts)."""
    from shapely.ops import unary_union

    shapes = [part_shape(p) for p in parts(spec, pose)]
    return shapes[0] if len(shapes) == 1 else unary_union(shapes)


__all__ = ["DISC_RADIUS", "Disc", "FIXTURE_SLOT", "FIXTURE_WALLS", "LocalBox", "Part", "ROUND_KINDS", "Rect", "TILT_TOL", "local_boxes",
           "part_shape", "parts", "shape", "world_box"]
