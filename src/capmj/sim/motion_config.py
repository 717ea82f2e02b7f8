"""The motion tuning of the arm: speeds, accelerations, tolerances, dwell and settle budgets.

One frozen value shared by line planning (:mod:`capmj.sim.line_plan`), tracking
(:mod:`capmj.sim.motion`) and the pick-and-place primitive (:mod:`capmj.sim.primitives`), so
each reads the same numbers; the planner's own numerical limits are constants of
:mod:`capmj.sim.line_plan`, not tuning.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class MotionConfig:
    """Motion tuning of the arm.  ``yaw_path_length`` times the wrist turn (rad) counts as path
    length, so a pure wrist rotation gets time and IK points like a move of that length does; 0.1 m
    per rad turns the largest placement turn (45°) into ~8 cm.  ``retreat`` is how far the tip at
    least rises straight up after letting go (after a place it rises on to the next primitive's
    transit height, see :meth:`capmj.sim.primitives.Primitives.transit_height`), so the cup leaves
    the released object vertically before the next move goes sideways.  ``plan_collisions`` off
gives the straight moves alone, unchecked (the motion before planning, for comparison)."""

    speed: float = 1.2            # m/s, free-space tip speed
    accel: float = 8.0            # m/s^2
    approach_speed: float = 0.25  # m/s for the last ``approach_gap`` before contact
    approach_gap: float = 0.02    # m
    overshoot: float = 0.03       # m searched beyond the expected contact height
    clearance: float = 0.06       # m between the lowest carried point and the highest object
    min_transit_z: float = 0.2    # m, tip height floor for transit
    joint_speed: float = 3.0      # rad/s (UR5e rating: 3.14)
    joint_accel: float = 20.0     # rad/s^2
    ik_dt: float = 0.02           # s between joint-space samples of a segment's timing
    path_step: float = 0.2        # m of path (``yaw_path_length`` per rad of wrist yaw) between IK solves before refinement
    yaw_path_length: float = 0.1  # m of path per rad of wrist yaw, for IK points and timing
    path_tol: float = 5e-4        # m tip error allowed by (Hermite) joint interpolation between IK solves
    path_rot_tol: float = 5e-3    # rad tool orientation error allowed the same way
    grip_dwell_steps: int = 10    # steps held after contact before lifting
    release_dwell_steps: int = 15
    settle_steps: int = 750       # max steps to let objects come to rest (1.5 s)
    settle_tol: float = 0.01      # m/s
    track_steps: int = 150        # max extra steps to converge at a segment end
    track_tol: float = 0.002      # m tip error accepted at a segment end
    retreat: float = 0.1          # m the tip rises after a release
    blend: float = 0.02           # m within which a corner of a multi-line move is rounded
    plan_collisions: bool = True  # check every move for collisions and plan around them (capmj.sim.collision)
    plan_clearance: float = 0.005  # m kept between the arm, tool or carried object and what they must not touch
    plan_max_checks: int = 30000  # configuration checks one planning query may spend before it fails
