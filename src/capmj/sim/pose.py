"""Pose helpers: one place for the rotation maths of the ``sim`` layer, on ``mujoco.mju_*`` where
that keeps results bit-identical.

Quaternions are **(w, x, y, z)** as in MuJoCo; angles in radians; yaw is the rotation about world +z.
(The motion, IK and primitive modules keep their own inlined maths for now: they are hot loops.)
"""

from __future__ import annotations

import math
from typing import Sequence

import mujoco
import numpy as np


def yaw_quat(yaw: float) -> list[float]:
    """Quaternion of a rotation by ``yaw`` about +z (exactly ``[cos(yaw/2), 0, 0, sin(yaw/2)]``)."""
    return [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]


def quat_to_mat(quat: Sequence[float]) -> np.ndarray:
    """3×3 rotation matrix of a unit quaternion.

    Written out rather than ``mju_quat2Mat``: the two differ in the last bit for most quaternions,
    and the planner API's yaw and footprints feed the commanded place yaw, so switching would move
    reference-plan trajectories by ~1e-16 rad and change their final states (measured: 8 of 25
    reference episodes).  Results must not change under a refactor; this is the formula capmj has
    always used.
    """
    w, x, y, z = (float(v) for v in quat)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def mat_to_quat(mat: np.ndarray) -> np.ndarray:
    """Unit quaternion of a 3×3 rotation matrix (``mju_mat2Quat``)."""
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(mat, dtype=np.float64).reshape(-1))
    return quat


def mat_yaw(mat: np.ndarray) -> float:
    """Yaw of a rotation: the angle of its x axis projected on the table (upright bodies)."""
    return math.atan2(mat[1, 0], mat[0, 0])


def lookat_quat(pos: Sequence[float], target: Sequence[float]) -> np.ndarray:
    """Quaternion of a MuJoCo camera at ``pos`` looking at ``target``, z up (cameras look along -z)."""
    f = np.asarray(target, float) - np.asarray(pos, float)
    f /= np.linalg.norm(f)
    right = np.cross(f, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    return mat_to_quat(np.column_stack([right, up, -f]))


def rotate_2d(xy: Sequence[float] | np.ndarray, yaw: float) -> np.ndarray:
    """Points ``(..., 2)`` rotated by ``yaw`` about the origin, counter-clockwise."""
    c, s = math.cos(yaw), math.sin(yaw)
    p = np.asarray(xy, dtype=float)
    return np.stack([c * p[..., 0] - s * p[..., 1], s * p[..., 0] + c * p[..., 1]], axis=-1)


__all__ = ["lookat_quat", "mat_to_quat", "mat_yaw", "quat_to_mat", "rotate_2d", "yaw_quat"]
