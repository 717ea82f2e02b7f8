"""``utils`` in sandboxed code: the pose helpers of Ravens' ``cliport.utils.utils`` that
CapRavens' prompt code calls, so that code runs as written.

Quaternions are (x, y, z, w) and Euler angles (roll, pitch, yaw) about the fixed x, y, z axes,
PyBullet's conventions (``getEulerFromQuaternion`` / ``getQuaternionFromEuler``), which the
planner API uses too (``get_obj_rot``, ``get_obj_pos_dict``).  Pure functions of their
arguments; :func:`utils_members` is what the sandbox's ``utils`` facade holds.

:class:`Coordinate`, the number type of the positions and quaternions the planner API returns, is
defined here because these helpers refuse it where CapRavens' code passed one number for a list;
the sandbox sits below the planner API (the API counts text with :mod:`~capmj.agents.sandbox.sizes`),
and :mod:`capmj.agents.api.values` re-exports it with the API's other values.
"""

from __future__ import annotations

import math
from typing import Any, NoReturn

import numpy as np

from capmj.errors import PortingDifference
from capmj.sim.pose import quat_euler_xyz, quat_to_mat, wxyz

ONE_ELEMENT_LISTS = ("get_obj_pos / get_obj_rot return one position [x, y, z] / one quaternion, not CapRavens' "
                     "one-element list of them: drop the [0] (here get_obj_pos(obj)[0] is already x)")
"""The message of indexing a :class:`Coordinate`."""


class Coordinate(float):
    """One number of a position or quaternion the API returned: a float in every way, except that
    indexing or unpacking it raises :class:`~capmj.errors.PortingDifference`.

    CapRavens' ``get_obj_pos`` returned a one-element list of positions, so its code writes
    ``get_obj_pos(obj)[0][2]`` or ``pos = get_obj_pos(obj)[0]; pos[1]``; here ``[0]`` is already
    x, and a plain float would fail with "'float' object is not subscriptable", which does not
    say why.  Arithmetic gives plain floats, numpy makes float64 arrays of it, ``repr`` is a float's.
    """

    __slots__ = ()

    def __getitem__(self, index: Any) -> NoReturn:
        raise PortingDifference(ONE_ELEMENT_LISTS)

    def __iter__(self) -> NoReturn:
        raise PortingDifference(ONE_ELEMENT_LISTS)


def _floats(value: Any, n: int, what: str) -> list[float]:
    if isinstance(value, Coordinate):  # get_obj_pos(obj)[0], written for CapRavens' lists
        raise PortingDifference(f"{what} is one number, {value!r}: {ONE_ELEMENT_LISTS}")
    arr = np.asarray(value, dtype=float).reshape(-1)
    if arr.shape != (n,):
        raise ValueError(f"{what} must be {n} numbers, got {value!r}")
    return [float(v) for v in arr]


def quatXYZW_to_eulerXYZ(quat: Any) -> tuple[float, float, float]:  # noqa: N802 - Ravens' name
    """(roll, pitch, yaw) in radians of an (x, y, z, w) quaternion."""
    roll, pitch, yaw = quat_euler_xyz(wxyz(_floats(quat, 4, "quaternion (x, y, z, w)")))
    return (roll, pitch, yaw)


def eulerXYZ_to_quatXYZW(euler: Any) -> tuple[float, float, float, float]:  # noqa: N802 - Ravens' name
    """The (x, y, z, w) quaternion of (roll, pitch, yaw) in radians."""
    r, p, y = (a / 2 for a in _floats(euler, 3, "Euler angles (roll, pitch, yaw)"))
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)


def apply(pose: Any, position: Any) -> tuple[Any, ...]:
    """A point given in the frame of ``pose`` = (position, (x, y, z, w) quaternion), in world
    coordinates: turned by the quaternion, then moved by the position (one [x, y, z] point, or
    a (3, n) array of points, as in Ravens)."""
    if not (isinstance(pose, (list, tuple)) and len(pose) == 2):
        raise ValueError(f"pose must be (position, quaternion), got {pose!r}")
    origin = _floats(pose[0], 3, "the pose's position [x, y, z]")
    rot = quat_to_mat(wxyz(_floats(pose[1], 4, "the pose's quaternion (x, y, z, w)")))
    pts = np.asarray(position, dtype=float)
    if pts.shape[:1] != (3,):
        raise ValueError(f"position must be [x, y, z] (or a (3, n) array), got {position!r}")
    out = rot @ pts.reshape(3, -1) + np.asarray(origin).reshape(3, 1)
    return tuple(out.reshape(pts.shape))


def utils_members() -> dict[str, object]:
    """The members of the sandbox's ``utils``."""
    return {"quatXYZW_to_eulerXYZ": quatXYZW_to_eulerXYZ, "eulerXYZ_to_quatXYZW": eulerXYZ_to_quatXYZW,
            "apply": apply}
