"""Pose helpers: one place for the rotation maths of the ``sim`` layer, on ``mujoco.mju_*`` where
that keeps results bit-identical.

Quaternions are **(w, x, y, z)** as in MuJoCo; angles in radians; yaw is the rotation about world +z.
(The motion, IK and primitive modules keep their own inlined maths for now: they are hot loops.)
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
import numpy.typing as npt

Vector = Sequence[float] | np.ndarray
"""A point, direction or quaternion: a sequence of floats or a 1-D numpy array."""


def yaw_quat(yaw: float) -> list[float]:
    """Quaternion of a rotation by ``yaw`` about +z (exactly ``[cos(yaw/2), 0, 0, sin(yaw/2)]``)."""
    return [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]


def quat_to_mat(quat: Vector) -> np.ndarray:
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


def quat_yaw(quat: Vector) -> float:
    """Yaw of a (w, x, y, z) quaternion: :func:`mat_yaw` of :func:`quat_to_mat`."""
    return mat_yaw(quat_to_mat(quat))


def quat_euler_xyz(quat: Vector) -> list[float]:
    """Roll, pitch, yaw (rad) of a (w, x, y, z) quaternion, as PyBullet's ``getEulerFromQuaternion``
    (extrinsic x, y, z).  Written out from the quaternion, in the terms capmj has always used, so
    the planner sees the same bits (a pitch of exactly 0 stays +0.0)."""
    w, x, y, z = (float(v) for v in quat)
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return [roll, pitch, yaw]


def xyzw(quat: Vector) -> tuple[float, float, float, float]:
    """A (w, x, y, z) quaternion reordered as (x, y, z, w): the planner API's, rerun's and Ravens' order."""
    w, x, y, z = (float(v) for v in quat)
    return (x, y, z, w)


def wxyz(quat: Vector) -> tuple[float, float, float, float]:
    """An (x, y, z, w) quaternion reordered as (w, x, y, z): MuJoCo's order."""
    x, y, z, w = (float(v) for v in quat)
    return (w, x, y, z)


def mat_to_quat(mat: np.ndarray) -> np.ndarray:
    """Unit quaternion of a 3×3 rotation matrix (``mju_mat2Quat``)."""
    quat = np.empty(4)
    import mujoco  # here, not at import: the task API (and the jailed host) needs no simulator

    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(mat, dtype=np.float64).reshape(-1))
    return quat


def mat_yaw(mat: np.ndarray) -> float:
    """Yaw of a rotation: the angle of its x axis projected on the table (upright bodies)."""
    return math.atan2(mat[1, 0], mat[0, 0])


def lookat_quat(pos: Vector, target: Vector) -> np.ndarray:
    """Quaternion of a MuJoCo camera at ``pos`` looking at ``target``, z up (cameras look along -z)."""
    f = np.asarray(target, float) - np.asarray(pos, float)
    f /= np.linalg.norm(f)
    right = np.cross(f, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    return mat_to_quat(np.column_stack([right, up, -f]))


def from_frame_2d(uv: npt.ArrayLike, yaw: float, origin: Vector = (0.0, 0.0)) -> np.ndarray:
    """Points ``(..., 2)`` given in a planar frame at ``origin`` turned by ``yaw``, in world
    coordinates: ``origin + R(yaw) uv``, summed as ``ox + c u − s v`` (left to right)."""
    c, s = math.cos(yaw), math.sin(yaw)
    p = np.asarray(uv, dtype=float)
    o = np.asarray(origin, dtype=float)
    return np.stack([o[0] + c * p[..., 0] - s * p[..., 1], o[1] + s * p[..., 0] + c * p[..., 1]], axis=-1)


def to_frame_2d(xy: npt.ArrayLike, yaw: float, origin: Vector = (0.0, 0.0)) -> np.ndarray:
    """World points ``(..., 2)`` in the planar frame at ``origin`` turned by ``yaw``:
    ``R(yaw)ᵀ (xy − origin)``, the inverse of :func:`from_frame_2d`."""
    c, s = math.cos(yaw), math.sin(yaw)
    d = np.asarray(xy, dtype=float) - np.asarray(origin, dtype=float)
    return np.stack([c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]], axis=-1)


def rotate_2d(xy: npt.ArrayLike, yaw: float) -> np.ndarray:
    """Points ``(..., 2)`` rotated by ``yaw`` about the origin, counter-clockwise."""
    c, s = math.cos(yaw), math.sin(yaw)
    p = np.asarray(xy, dtype=float)
    return np.stack([c * p[..., 0] - s * p[..., 1], s * p[..., 0] + c * p[..., 1]], axis=-1)


__all__ = ["Vector", "from_frame_2d", "lookat_quat", "mat_to_quat", "mat_yaw", "quat_euler_xyz", "quat_to_mat", "quat_yaw",
           "rotate_2d", "to_frame_2d", "wxyz", "xyzw", "yaw_quat"]
