"""Frozen snapshots of a scene's object poses.

Success predicates, reporters and loggers work on these snapshots rather than on ``MjData``: the
snapshot is cheap to copy, hashable into JSON, and can be built by hand in unit tests to check a
predicate against near misses without running physics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Iterator, Mapping

import numpy as np

from capmj.sim.objects import ObjectSpec


@dataclass(frozen=True)
class Pose:
    """Position (m) and orientation quaternion, **(w, x, y, z)** as in MuJoCo."""

    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)

    @property
    def rotation(self) -> np.ndarray:
        w, x, y, z = self.quat
        return np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )

    @property
    def yaw(self) -> float:
        """Rotation about world z of the body x axis (meaningful for upright objects)."""
        r = self.rotation
        return math.atan2(r[1, 0], r[0, 0])

    @property
    def tilt(self) -> float:
        """Smallest angle (rad) between world z and any body axis (±x, ±y, ±z).

        A cube resting on any face has tilt 0; a cube balanced on an edge has tilt 45°.
        """
        r = self.rotation
        return float(math.acos(min(1.0, float(np.max(np.abs(r[2, :]))))))

    @property
    def xquat(self) -> tuple[float, float, float, float]:
        """The same quaternion as (x, y, z, w), the planner API's and rerun's convention."""
        w, x, y, z = self.quat
        return (x, y, z, w)


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
        poses = {o.obj_id: Pose(o.pos, (math.cos(o.yaw / 2), 0.0, 0.0, math.sin(o.yaw / 2))) for o in objs}
        return cls(objs, poses)
