"""From segments to objects: kind, size class, pose, box and confidence of each detection.

The object kinds are told apart by shape alone, using the catalogue's dimensions
(:mod:`capmj.sim.objects`, the robot's prior knowledge of the objects it works with; never an
episode's specs):

* a *flat* segment is a zone: a square whose side gives its scale;
* a raised segment wider than 9 cm both ways is a bowl's rim (its floor, a low segment of the
  same colour inside the rim, is absorbed);
* a raised segment longer than 8 cm but narrow is a fixture's L;
* a raised segment whose named (up-facing) cells are under half of it is a ball: only the cap
  of a sphere faces up;
* anything else is a block, whose size class is the nearest catalogue edge to its top's side.

Positions are geometric centres, as the planner API reports them (a fixture's is its body
origin, slot (0, 0), which is what the API reports for it).  The confidence multiplies a colour
margin (how much nearer the chosen colour is than the runner-up) by a shape agreement (how
close the measured footprint is to the catalogue's).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from capmj.perception.footprint import Rect, fit_l, l_corners, min_area_rect, square_yaw
from capmj.perception.segment import Segment
from capmj.sim.objects import (
    BALL_RADIUS,
    BLOCK_SIZES,
    BOWL_HEIGHT,
    BOWL_RADIUS,
    FIXED_KINDS,
    FIXTURE_HEIGHT,
    ZONE_HEIGHT,
    ZONE_SIZE,
)
from capmj.sim.palette import COLOR_NAMES
from capmj.sim.shapes import FIXTURE_RECT

BOWL_MIN_SIDE = 0.09
FIXTURE_MIN_LENGTH = 0.08
BALL_MAX_NAMED = 0.5
FLOOR_MAX_HEIGHT = 0.012
"""A raised segment lower than this is a bowl's floor (4 mm), or noise if no bowl surrounds it."""

Box = tuple[tuple[float, float, float], tuple[float, float, float]]


@dataclass(frozen=True)
class Detection:
    """One perceived object (metres, radians)."""

    kind: str
    """block, zone, bowl, ball or fixture."""
    color: str
    """A palette name (:data:`capmj.sim.palette.COLOR_NAMES`)."""
    size: str | None
    """tiny, small or big for blocks; None otherwise."""
    scale: float
    """A zone's footprint over the catalogue's 12 cm (1.0 for the other kinds)."""
    position: tuple[float, float, float]
    """Geometric centre (a fixture: its origin, slot (0, 0))."""
    yaw: float
    """About +z: blocks and zones in [-π/4, π/4) (squares), fixtures in (-π, π], 0 for round kinds."""
    aabb: Box
    """World axis-aligned box (min corner, max corner)."""
    confidence: float
    """In [0, 1]: colour margin x shape agreement."""

    @property
    def fixed(self) -> bool:
        """Whether the kind is one the robot cannot pick (the catalogue's own set, as in state mode)."""
        return self.kind in FIXED_KINDS


def _rect(xy: np.ndarray, cell: float) -> Rect:
    """The footprint of cells that each hold the highest point falling in them.

    A cell the object's edge crosses holds the object's point, so the occupied cells overhang the
    edge by half a cell on average: their *centres* lie on the edge on average, and the
    rectangle of the centres is unbiased (the cell corners would add a cell to every side).
    """
    del cell
    return min_area_rect(xy)


def _square_box(x: float, y: float, half: float, yaw: float, z0: float, z1: float) -> Box:
    e = half * (abs(math.cos(yaw)) + abs(math.sin(yaw)))
    return ((x - e, y - e, z0), (x + e, y + e, z1))


def _colour_confidence(seg: Segment) -> float:
    total = seg.delta_e + seg.runner_up
    return 1.0 if total <= 0 else float(seg.runner_up / total)


def _agreement(measured: float, expected: float, tolerance: float) -> float:
    return float(max(0.0, 1.0 - abs(measured - expected) / tolerance))


def zone(seg: Segment, cell: float) -> Detection:
    r = _rect(seg.xy, cell)
    side = (r.length + r.width) / 2
    scale = round(side / ZONE_SIZE, 2)
    yaw = square_yaw(r)
    conf = _colour_confidence(seg) * _agreement(r.width / max(r.length, 1e-9), 1.0, 0.5)
    return Detection("zone", COLOR_NAMES[seg.colour], None, scale, (r.cx, r.cy, ZONE_HEIGHT / 2), yaw,
                     _square_box(r.cx, r.cy, side / 2, yaw, 0.0, ZONE_HEIGHT), conf)


def block(seg: Segment, cell: float) -> Detection:
    r = _rect(seg.xy, cell)
    side = (r.length + r.width) / 2
    size, edge = min(BLOCK_SIZES.items(), key=lambda kv: abs(kv[1] - side))
    top = float(np.median(seg.heights))
    yaw = square_yaw(r)
    x, y, z = r.cx, r.cy, top - edge / 2
    conf = _colour_confidence(seg) * _agreement(side, edge, 0.01)
    return Detection("block", COLOR_NAMES[seg.colour], size, 1.0, (x, y, z), yaw,
                     _square_box(x, y, edge / 2, yaw, z - edge / 2, z + edge / 2), conf)


def bowl(seg: Segment, cell: float) -> Detection:
    r = _rect(seg.all_xy, cell)
    diameter = (r.length + r.width) / 2
    conf = _colour_confidence(seg) * _agreement(diameter, 2 * BOWL_RADIUS, 0.03)
    return Detection("bowl", COLOR_NAMES[seg.colour], None, 1.0, (r.cx, r.cy, BOWL_HEIGHT / 2), 0.0,
                     ((r.cx - BOWL_RADIUS, r.cy - BOWL_RADIUS, 0.0), (r.cx + BOWL_RADIUS, r.cy + BOWL_RADIUS, BOWL_HEIGHT)),
                     conf)


def ball(seg: Segment, cell: float) -> Detection:
    # The cap is centred on the apex, so its centroid is the centre; the flanks give the size.
    x, y = (float(v) for v in seg.xy.mean(axis=0))
    r = _rect(seg.all_xy, cell)
    z = float(np.max(seg.heights)) - BALL_RADIUS
    conf = _colour_confidence(seg) * _agreement((r.length + r.width) / 2, 2 * BALL_RADIUS, 0.03)
    b = BALL_RADIUS
    return Detection("ball", COLOR_NAMES[seg.colour], None, 1.0, (x, y, z), 0.0,
                     ((x - b, y - b, z - b), (x + b, y + b, z + b)), conf)


def fixture(seg: Segment, cell: float) -> Detection:
    fit = fit_l(seg.all_xy, cell)
    # The cells' extent along the fitted L's own axes (its enclosing rectangle, 10 x 6 cm).
    c, s = math.cos(fit.yaw), math.sin(fit.yaw)
    u, v = seg.all_xy @ np.array([c, s]), seg.all_xy @ np.array([-s, c])
    conf = (_colour_confidence(seg) * _agreement(float(np.ptp(u)), FIXTURE_RECT[0], 0.03)
            * _agreement(float(np.ptp(v)), FIXTURE_RECT[1], 0.03) * max(0.0, 1.0 - fit.mismatch))
    corners = l_corners(fit)
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    return Detection("fixture", COLOR_NAMES[seg.colour], None, 1.0, (fit.x, fit.y, FIXTURE_HEIGHT / 2), fit.yaw,
                     ((float(lo[0]), float(lo[1]), 0.0), (float(hi[0]), float(hi[1]), FIXTURE_HEIGHT)), conf)


def kind_of(seg: Segment, cell: float) -> str:
    """The kind a segment's shape says it is (see the module docstring); "floor" for a low
    raised surface (a bowl's floor, or a sliver of a flat object's edge), never an object."""
    if seg.layer == "flat":
        return "zone"
    if float(np.median(seg.heights)) < FLOOR_MAX_HEIGHT:
        return "floor"
    r = _rect(seg.all_xy, cell)
    if r.width > BOWL_MIN_SIDE:
        return "bowl"
    if r.length > FIXTURE_MIN_LENGTH:
        return "fixture"
    if len(seg.xy) < BALL_MAX_NAMED * len(seg.all_xy):
        return "ball"
    return "block"


def detect(segments: list[Segment], cell: float) -> list[Detection]:
    """Detections of all segments, floors left out."""
    builders = {"zone": zone, "block": block, "bowl": bowl, "ball": ball, "fixture": fixture}
    out = []
    for s in segments:
        k = kind_of(s, cell)
        if k != "floor":
            out.append(builders[k](s, cell))
    return out


__all__ = ["Detection", "detect", "kind_of"]
