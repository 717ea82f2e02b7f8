"""What an object covers of the table seen from above: the one footprint model of capmj.

A footprint is a function of an object's spec and pose only (no MuJoCo model), so the planner API
(:mod:`capmj.agents.api.footprints`, live world poses or perceived ones) and the success predicates
(:mod:`capmj.tasks.predicates`, a settled :class:`~capmj.sim.state.SceneState`) measure the same
table.  Before this module they measured three different ones: the planner read its geoms' boxes
and switched to a world box beyond 20° of tilt, the judge rebuilt centred boxes from the half
extents beyond 15°, and the fixture's walls had a third copy in the perceived API.

The model: bowls and balls are discs (their outline whatever their yaw); blocks, zones and each
wall of a fixture (:data:`capmj.sim.shapes.FIXTURE_WALLS`) are rectangles in the object's frame
(:func:`local_boxes`), turned by its yaw;
an object tilted more than :data:`TILT_TOL` covers the world xy box of those boxes instead.

The arm's motion does not use this: it plans descents and transits on coarse axis-aligned world
boxes (:meth:`capmj.sim.primitives.Primitives.coarse_top_under`), where an overestimate is safe.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from capmj.sim.objects import BALL_RADIUS, BOWL_RADIUS, ObjectSpec
from capmj.sim.pose import from_frame_2d
from capmj.sim.shapes import FIXTURE_WALLS, LocalBox
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


__all__ = ["DISC_RADIUS", "Disc", "Part", "ROUND_KINDS", "Rect", "TILT_TOL", "local_boxes",
           "part_shape", "parts", "shape", "world_box"]
