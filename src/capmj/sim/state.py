"""Frozen snapshots of a scene's object poses.

Success predicates, reporters and loggers work on these snapshots rather than on ``MjData``: the
snapshot is cheap to copy, hashable into JSON, and can be built by hand in unit tests to check a
predicate against near misses without running physics.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Iterator, Mapping, Sequence

import numpy as np

from capmj.sim.objects import ObjectSpec
from capmj.sim.pose import mat_yaw, quat_to_mat, xyzw, yaw_quat


@dataclass(frozen=True)
class Pose:
    """Position (m) and orientation quaternion, **(w, x, y, z)** as in MuJoCo."""

    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)

    @classmethod
    def of(cls, pos: Sequence[float], quat: Sequence[float]) -> Pose:
        """A pose from any sequences (numpy rows included), stored as plain float tuples."""
        x, y, z = (float(v) for v in pos)
        w, qx, qy, qz = (float(v) for v in quat)
        return cls((x, y, z), (w, qx, qy, qz))

    @property
    def rotation(self) -> np.ndarray:
        return quat_to_mat(self.quat)

    @property
    def yaw(self) -> float:
        """Rotation about world z of the body x axis (meaningful for upright objects)."""
        return mat_yaw(self.rotation)

    @property
    def tilt(self) -> float:
        """Smallest angle (rad) between world z and any body axis (±x, ±y, ±z).

        A cube resting on any face has tilt 0; a cube balanced on an edge has tilt 45°.
        """
        r = self.rotation
        return float(math.acos(min(1.0, float(np.max(np.abs(r[2, :]))))))

    @property
    def quat_xyzw(self) -> tuple[float, float, float, float]:
        """The same quaternion as (x, y, z, w), the planner API's and rerun's convention."""
        return xyzw(self.quat)

    @property
    def xquat(self) -> tuple[float, float, float, float]:
        """Deprecated name of :attr:`quat_xyzw` (it read like MuJoCo's ``data.xquat``, which is w, x, y, z)."""
        warnings.warn("Pose.xquat is deprecated: use Pose.quat_xyzw (the same x, y, z, w quaternion)",
                      DeprecationWarning, stacklevel=2)
        return self.quat_xyzw


@dataclass(frozen=True)
class SceneState:
    """Object specs plus their current poses; ``time`` is simulated seconds."""

    objects: tuple[ObjectSpec, ...]
    poses: Mapping[int, Pose]
    time: float = 0.0
    held: int | None = None
    _by_id: Mapping[int, ObjectSpec] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_by_id", {o.obj_id: o for o in self.objects})

    def spec(self, obj_id: int) -> ObjectSpec:
        return self._by_id[obj_id]

    def pos(self, obj_id: int) -> np.ndarray:
        return np.asarray(self.poses[obj_id].pos, dtype=float)

    def __iter__(self) -> Iterator[tuple[ObjectSpec, Pose]]:
        for o in self.objects:
            yield o, self.poses[o.obj_id]

    def of_kind(self, kind: str) -> list[ObjectSpec]:
        return [o for o in self.objects if o.kind == kind]

    @classmethod
    def from_specs(cls, objects: tuple[ObjectSpec, ...] | list[ObjectSpec]) -> "SceneState":
        """The state in which every object sits at its spec pose (a scene's initial layout)."""
        objs = tuple(objects)
        poses = {o.obj_id: Pose.of(o.pos, yaw_quat(o.yaw)) for o in objs}
        return cls(objs, poses)
