"""Table geometry of the planner API: object footprints and the free-space queries built on them.

A footprint is what an object covers of the table seen from above, and it is capmj's one model of
it, :mod:`capmj.sim.footprint` (the success predicates use the same): blocks, zones and fixture
walls are oriented rectangles at the current yaw, bowls and balls discs, and an object tilted more
than :data:`~capmj.sim.footprint.TILT_TOL` (15°) covers its world xy box.  On footprints rest the
questions plan code asks about the table: how far a point is from an object, how high something
put down at a point rests, what lies on what, what occupies a point or an object, and where a free
position is.

:class:`Footprints` reads specs and poses live through the callables it is given (normally
:meth:`Footprints.from_world`; the perceived API passes its detections), so every query answers
for the scene as it is now.  It knows nothing of names, episodes or call logging: that is the
facade in :mod:`capmj.agents.api.planner_api`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Callable, Iterable, Sequence

import numpy as np

from capmj.sim import footprint
from capmj.sim.bounds import WORKSPACE, Bounds
from capmj.sim.footprint import Disc
from capmj.sim.objects import BOWL_FLOOR, BOWL_HEIGHT, BOWL_INNER_RADIUS, ObjectSpec
from capmj.sim.pose import Vector
from capmj.sim.state import Pose

if TYPE_CHECKING:
    from capmj.sim.world import World

REACH_RADIUS = 0.84
"""Object centres farther than this (m, in xy) from the robot base are not offered as free
positions: the far workspace corners (e.g. (0.73, 0.48)) are out of the UR5e's reach."""
FREE_GRID_STEP = 0.005
"""Pitch (m) of the candidate grid of :meth:`Footprints.free_position`."""
FREE_CLEARANCE = 0.045
"""Default clearance (m) from a free position to every footprint: a big block (0.06 m, half
diagonal 0.042 m) fits there at any yaw."""


def distances(px: np.ndarray, py: np.ndarray, parts: np.ndarray) -> np.ndarray:
    """(n, k) distances (m) from points to footprint parts (0 inside).

    ``parts`` is a (k, 7) array of rows [cx, cy, cos, sin, hx, hy, disc] as made by
    :meth:`Footprints.part_arrays`; a disc row has its radius in hx.
    """
    dx = px[:, None] - parts[None, :, 0]
    dy = py[:, None] - parts[None, :, 1]
    c, s = parts[None, :, 2], parts[None, :, 3]
    lx = np.abs(c * dx + s * dy) - parts[None, :, 4]
    ly = np.abs(-s * dx + c * dy) - parts[None, :, 5]
    rect = np.hypot(np.maximum(lx, 0.0), np.maximum(ly, 0.0))
    disc = np.maximum(np.hypot(dx, dy) - parts[None, :, 4], 0.0)
    return np.where(parts[None, :, 6] > 0, disc, rect)


class Footprints:
    """Footprints of a scene's objects and the table queries on them, read live.

    ``objects`` gives the current object specs, ``pose`` and ``top_z`` an object's pose and top
    height (see :meth:`from_world`, which builds all three from a
    :class:`~capmj.sim.world.World`).
    """

    def __init__(
        self,
        objects: Callable[[], Sequence[ObjectSpec]],
        pose: Callable[[int], Pose],
        top_z: Callable[[int], float],
    ) -> None:
        self._objects = objects
        self._pose = pose
        self._top_z = top_z

    @classmethod
    def from_world(cls, world: World) -> Footprints:
        """Footprints of a live world: objects and poses are read from it on every query."""
        return cls(lambda: tuple(world.objects), world.pose, world.top_z)

    def _pos(self, oid: int) -> np.ndarray:
        return np.asarray(self._pose(oid).pos, float)

    # ================================================================== footprints
    def parts(self, o: ObjectSpec) -> list[footprint.Part]:
        """Footprint parts of an object now (:func:`capmj.sim.footprint.parts` at its pose)."""
        return footprint.parts(o, self._pose(o.obj_id))

    def part_arrays(self, objs: Sequence[ObjectSpec]) -> tuple[np.ndarray, np.ndarray]:
        """Footprint parts of ``objs`` as one (k, 7) array [cx, cy, cos, sin, hx, hy, disc] and
        the index into ``objs`` of every part."""
        rows, owner = [], []
        for k, o in enumerate(objs):
            for p in self.parts(o):
                if isinstance(p, Disc):
                    rows.append((p.cx, p.cy, 1.0, 0.0, p.r, p.r, 1.0))
                else:
                    rows.append((p.cx, p.cy, math.cos(p.yaw), math.sin(p.yaw), p.hx, p.hy, 0.0))
                owner.append(k)
        return np.asarray(rows, float).reshape(-1, 7), np.asarray(owner, int)

    def distance(self, xy: Vector, o: ObjectSpec) -> float:
        """Distance (m) from a point to an object's footprint (0 inside)."""
        parts, _ = self.part_arrays([o])
        return float(distances(np.array([float(xy[0])]), np.array([float(xy[1])]), parts).min())

    def polygon(self, o: ObjectSpec):
        """An object's footprint now as a shapely geometry (:func:`capmj.sim.footprint.shape`)."""
        return footprint.shape(o, self._pose(o.obj_id))

    # ================================================================== what rests where
    def support_z(self, xy: Vector, exclude: set[int]) -> float:
        """Height (m) an object put down at ``xy`` rests on: the table (0), the top of whatever
        covers the point, or the floor of a bowl (or what lies in it) when inside its wall.

        Answers on exact footprints at the point itself, and zones (flat marks) do not count.  The
        arm's own descent uses the coarser :meth:`capmj.sim.primitives.Primitives.coarse_top_under`
        (where it may first touch something, e.g. a bowl's rim, not its floor)."""
        z = 0.0
        for o in self._objects():
            if o.obj_id in exclude or o.kind == "zone":  # zones are flat marks, not surfaces
                continue
            if self.distance(xy, o) > 1e-3:
                continue
            if o.kind == "bowl":
                c = self._pos(o.obj_id)
                if math.hypot(xy[0] - c[0], xy[1] - c[1]) < BOWL_INNER_RADIUS:
                    z = max(z, float(c[2]) - BOWL_HEIGHT / 2 + BOWL_FLOOR)
                    continue
            z = max(z, self._top_z(o.obj_id))
        return z

    def resting_on(self, o: ObjectSpec) -> list[ObjectSpec]:
        """Movable objects lying on top of ``o`` (centre over its footprint and above its top)."""
        top = self._top_z(o.obj_id)
        out = []
        for other in self._objects():
            if other.fixed or other.obj_id == o.obj_id:
                continue
            p = self._pos(other.obj_id)
            if p[2] > top - 0.005 and self.distance(p[:2], o) <= 0.0:
                out.append(other)
        return out

    # ================================================================== occupancy
    def overlapping(self, t: ObjectSpec) -> list[ObjectSpec]:
        """Every other object whose footprint overlaps ``t``'s (e.g. blocks in a zone, or the zone
        under a block and whatever is stacked on it)."""
        objs = self._objects()
        mine = self.polygon(t)
        return [o for o in objs if o.obj_id != t.obj_id and mine.intersection(self.polygon(o)).area > 1e-6]

    def within(self, xy: Vector, r: float) -> list[ObjectSpec]:
        """Every object whose footprint lies within ``r`` m of the point ``xy``."""
        objs = self._objects()
        parts, owner = self.part_arrays(objs)
        if not len(parts):
            return []
        d = distances(np.array([xy[0]]), np.array([xy[1]]), parts)[0]
        hit = set(owner[d <= r].tolist())
        return [o for k, o in enumerate(objs) if k in hit]

    def free_position(self, area: Sequence[float], r: float, rng: np.random.Generator,
                      reserved: Iterable[Vector] = ()) -> list[float]:
        """A random free position [x, y, 0.0] (m) in ``area`` = (xmin, ymin, xmax, ymax).

        Vectorised search over a :data:`FREE_GRID_STEP` grid centred in the area (clipped to the
        workspace, :data:`capmj.sim.bounds.WORKSPACE`, and, when large enough, shrunk by ``r``) and within :data:`REACH_RADIUS`: every
        footprint part, and a disc of radius ``r`` around every ``reserved`` xy, clears the cells
        closer than ``r`` in its own grid window; one free cell is drawn with ``rng`` (the same
        scene and draws give the same positions).  ``reserved`` is consumed only after the area
        checks, so a lazy iterable reports a bad area before a bad reserved entry.  Raises
        ValueError when the area is empty, outside the workspace, or nothing is free.
        """
        xmin, ymin, xmax, ymax = (float(v) for v in area)
        if xmin > xmax or ymin > ymax:
            raise ValueError(f"area {area} is empty: the order is (xmin, ymin, xmax, ymax)")
        # centres stay inside the workspace and, when the area is large enough, r from its border
        b = Bounds(xmin, xmax, ymin, ymax).intersect(WORKSPACE)
        if b.empty:
            raise ValueError(f"area {tuple(area)} lies outside the workspace {WORKSPACE.xyxy}")
        if b.xmax - b.xmin >= 2 * r + FREE_GRID_STEP and b.ymax - b.ymin >= 2 * r + FREE_GRID_STEP:
            b = b.shrink(r)
        bx0, by0, bx1, by1 = b.xyxy
        nx = int(math.floor((bx1 - bx0) / FREE_GRID_STEP)) + 1
        ny = int(math.floor((by1 - by0) / FREE_GRID_STEP)) + 1
        xs = bx0 + FREE_GRID_STEP * np.arange(nx) + ((bx1 - bx0) - FREE_GRID_STEP * (nx - 1)) / 2
        ys = by0 + FREE_GRID_STEP * np.arange(ny) + ((by1 - by0) - FREE_GRID_STEP * (ny - 1)) / 2
        free = np.hypot(xs[:, None], ys[None, :]) <= REACH_RADIUS
        parts, _ = self.part_arrays(self._objects())
        extra = list(reserved)
        if extra:
            discs = np.array([(p[0], p[1], 1.0, 0.0, r, r, 1.0) for p in extra], float)
            parts = np.vstack([parts, discs]) if len(parts) else discs
        for part in parts:  # each part can only block the grid window around it
            reach = (part[4] if part[6] else math.hypot(part[4], part[5])) + r
            i0, i1 = np.searchsorted(xs, [part[0] - reach, part[0] + reach])
            j0, j1 = np.searchsorted(ys, [part[1] - reach, part[1] + reach])
            if i0 >= i1 or j0 >= j1:
                continue
            wx, wy = np.meshgrid(xs[i0:i1], ys[j0:j1], indexing="ij")
            d = distances(wx.ravel(), wy.ravel(), part[None, :])[:, 0].reshape(wx.shape)
            free[i0:i1, j0:j1] &= d >= r
        idx = np.flatnonzero(free)
        if not len(idx):
            raise ValueError(f"no free position with clearance {r} m in area "
                             f"({xmin:.3f}, {ymin:.3f}, {xmax:.3f}, {ymax:.3f})")
        k = int(idx[int(rng.integers(len(idx)))])
        return [round(float(xs[k // ny]), 6), round(float(ys[k % ny]), 6), 0.0]


__all__ = ["FREE_CLEARANCE", "FREE_GRID_STEP", "Footprints", "REACH_RADIUS", "distances"]
