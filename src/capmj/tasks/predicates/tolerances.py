"""The originals' tolerances (Ravens/CapRavens) shared by the predicates and the tasks.

The spec lists them once ("Tolerances of the originals"): plane position 0.01 m (0.05 m for
bowls), SE(2) rotation 15°, vertical 0.015 m; the tilt limit is the footprint model's
(:data:`capmj.sim.footprint.TILT_TOL`), so the planner and the judge call the same objects
toppled.  Tolerances that belong to one structure (rows, circles, fixture slots) live with it.
"""

from __future__ import annotations

import math

from capmj.sim.footprint import TILT_TOL

PLANE_TOL = 0.01
"""Plane position tolerance (m) of a pose match."""
BOWL_TOL = 0.05
"""A centre within this xy distance (m) of a bowl centre is "in" the bowl (when below the rim)."""
Z_TOL = 0.015
"""Vertical tolerance (m): resting heights and stack gaps."""
YAW_TOL = math.radians(15.0)
"""Rotation tolerance (rad) of an SE(2) pose match."""
STACK_AXIS_TOL = 0.02
"""Every block of a stack has its xy centre within this distance (m) of the stack axis."""
MOVE_TOL = 0.03
"""An object "did not move" when its centre ends within this distance (m) of its start."""

__all__ = ["BOWL_TOL", "MOVE_TOL", "PLANE_TOL", "STACK_AXIS_TOL", "TILT_TOL", "YAW_TOL", "Z_TOL"]
