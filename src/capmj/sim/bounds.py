"""Axis-aligned bounds on the table, and the workspace: the one place its extent is written.

The workspace is the Ravens table top, x ∈ [0.25, 0.75], y ∈ [−0.5, 0.5], z ∈ [0, 0.3] (metres,
robot base at the origin, +x away from it).  Everything that needs it — the heightmap camera, the
task areas, spawning, the planner's free-position search — reads :data:`WORKSPACE`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np


@dataclass(frozen=True)
class Bounds:
    """``xmin ≤ x ≤ xmax``, ``ymin ≤ y ≤ ymax`` (and ``zmin ≤ z ≤ zmax``, unbounded by default), in metres."""

    xmin: float
    xmax: float
    ymin: float
    ymax: float
    zmin: float = -math.inf
    zmax: float = math.inf

    @classmethod
    def of(cls, region: Bounds | Sequence[float]) -> Bounds:
        """A ``Bounds`` itself or one from ``(xmin, xmax, ymin, ymax)``.  (Area names such as
        "top left" are task vocabulary: :func:`capmj.tasks.spawn.region_bounds` resolves them.)"""
        if isinstance(region, Bounds):
            return region
        if isinstance(region, str):
            raise TypeError(f"Bounds.of takes numbers, not the area name {region!r}; "
                            "use capmj.tasks.spawn.region_bounds")
        return cls(*(float(v) for v in region))

    @property
    def xy(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)``."""
        return (self.xmin, self.xmax, self.ymin, self.ymax)

    @property
    def xyxy(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)``: shapely's order, and the planner API's for areas."""
        return (self.xmin, self.ymin, self.xmax, self.ymax)

    @property
    def center(self) -> tuple[float, float]:
        return ((self.xmin + self.xmax) / 2, (self.ymin + self.ymax) / 2)

    @property
    def empty(self) -> bool:
        return self.xmin > self.xmax or self.ymin > self.ymax

    def as_array(self) -> np.ndarray:
        """Rows x, y, z; columns min, max (the layout of the heightmap code)."""
        return np.array([[self.xmin, self.xmax], [self.ymin, self.ymax], [self.zmin, self.zmax]], dtype=np.float64)

    def shrink(self, m: float) -> Bounds:
        """The rectangle moved inwards by ``m`` on every side (z unchanged)."""
        return Bounds(self.xmin + m, self.xmax - m, self.ymin + m, self.ymax - m, self.zmin, self.zmax)

    def intersect(self, other: Bounds) -> Bounds:
        return Bounds(max(self.xmin, other.xmin), min(self.xmax, other.xmax),
                      max(self.ymin, other.ymin), min(self.ymax, other.ymax),
                      max(self.zmin, other.zmin), min(self.zmax, other.zmax))

    def contains(self, x, y, margin: float = 0.0):
        """Whether (x, y) lies inside the rectangle grown by ``margin``; works on arrays."""
        return ((x >= self.xmin - margin) & (x <= self.xmax + margin)
                & (y >= self.ymin - margin) & (y <= self.ymax + margin))


WORKSPACE = Bounds(0.25, 0.75, -0.5, 0.5, 0.0, 0.3)
"""The Ravens workspace (see the module docstring)."""

__all__ = ["WORKSPACE", "Bounds"]
