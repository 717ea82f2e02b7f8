"""The perceiver's whole input: RGB, metric depth and calibration of each camera, savable to disk.

A real robot has images and a calibration, not a simulator.  :class:`RGBDBundle` is exactly that
and nothing more, so anything that consumes it cannot cheat by accident: it has no object ids, no
segmentation, no model.  It round-trips through one ``.npz`` file (:meth:`RGBDBundle.save`,
:meth:`RGBDBundle.load`), which is how the isolation test feeds the perceiver in a process that
has no world at all, and how a failing scene can be attached to a bug report.

Conventions are those of :mod:`capmj.sim.cameras` (repeated here because this module must not
import it: it imports MuJoCo): images row-major with row 0 at the top, depth in metres along the
optical axis, intrinsics ``[[fx,0,cx],[0,fy,cy],[0,0,1]]`` with pixel ``(v, u)`` centred at
``(u + 0.5, v + 0.5)``, extrinsics the camera-to-world pose with OpenCV axes (x right, y down,
z forward).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

import numpy as np

from capmj.errors import ConfigError


def _readonly(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class CameraImage:
    """One calibrated RGB-D view (arrays are read-only copies)."""

    name: str
    rgb: np.ndarray
    """uint8 (H, W, 3)."""
    depth: np.ndarray
    """float32 (H, W) metres along the optical axis; the far plane where nothing is seen."""
    intrinsics: np.ndarray
    """float64 (3, 3) pinhole matrix."""
    extrinsics: np.ndarray
    """float64 (4, 4) camera-to-world, OpenCV camera axes."""

    def __post_init__(self) -> None:
        rgb = np.ascontiguousarray(self.rgb, dtype=np.uint8)
        depth = np.ascontiguousarray(self.depth, dtype=np.float32)
        k = np.array(self.intrinsics, dtype=np.float64)
        t = np.array(self.extrinsics, dtype=np.float64)
        if rgb.ndim != 3 or rgb.shape[2] != 3 or depth.shape != rgb.shape[:2]:
            raise ConfigError(f"camera {self.name!r}: rgb {rgb.shape} and depth {depth.shape} do not match")
        if k.shape != (3, 3) or t.shape != (4, 4):
            raise ConfigError(f"camera {self.name!r}: intrinsics must be 3x3 and extrinsics 4x4")
        for field, value in (("rgb", rgb), ("depth", depth), ("intrinsics", k), ("extrinsics", t)):
            object.__setattr__(self, field, _readonly(value.copy()))

    @property
    def shape(self) -> tuple[int, int]:
        return int(self.depth.shape[0]), int(self.depth.shape[1])

    def points(self) -> np.ndarray:
        """World point (H, W, 3) seen at every pixel, from the depth (float64)."""
        h, w = self.shape
        v, u = np.mgrid[0:h, 0:w]
        d = self.depth.astype(np.float64)
        k = self.intrinsics
        cam = np.stack([(u + 0.5 - k[0, 2]) / k[0, 0] * d, (v + 0.5 - k[1, 2]) / k[1, 1] * d, d], axis=-1)
        return cam @ self.extrinsics[:3, :3].T + self.extrinsics[:3, 3]


@dataclass(frozen=True, eq=False)
class RGBDBundle:
    """The views one perception call sees, in a fixed order (the order of the cameras given)."""

    views: tuple[CameraImage, ...]

    def __post_init__(self) -> None:
        names = [v.name for v in self.views]
        if not names or len(set(names)) != len(names):
            raise ConfigError(f"an RGB-D bundle needs at least one view with unique names, got {names}")

    @classmethod
    def from_frames(cls, frames: Iterable[Any]) -> RGBDBundle:
        """A bundle from rendered frames (anything with ``name``, ``rgb``, ``depth``, ``intrinsics``
        and ``extrinsics``, e.g. :class:`capmj.sim.cameras.CameraFrame`).  Only those five fields
        are copied: a frame's segmentation never reaches the perceiver."""
        return cls(tuple(CameraImage(f.name, f.rgb, f.depth, f.intrinsics, f.extrinsics) for f in frames))

    def view(self, name: str) -> CameraImage:
        for v in self.views:
            if v.name == name:
                return v
        raise ConfigError(f"no view {name!r}; views: {', '.join(v.name for v in self.views)}")

    def save(self, path: str | Path) -> Path:
        """Write the bundle to one compressed ``.npz`` (arrays per view plus a JSON list of names)."""
        path = Path(path)
        arrays: dict[str, np.ndarray] = {"names": np.array(json.dumps([v.name for v in self.views]))}
        for i, v in enumerate(self.views):
            arrays.update({f"rgb{i}": v.rgb, f"depth{i}": v.depth, f"K{i}": v.intrinsics, f"T{i}": v.extrinsics})
        with open(path, "wb") as fh:
            np.savez_compressed(fh, **arrays)  # type: ignore[arg-type]
        return path

    @classmethod
    def load(cls, path: str | Path) -> RGBDBundle:
        """Read a bundle written by :meth:`save` (no pickles: ``allow_pickle=False``)."""
        with np.load(Path(path), allow_pickle=False) as data:
            names = json.loads(str(data["names"]))
            return cls(tuple(CameraImage(n, data[f"rgb{i}"], data[f"depth{i}"], data[f"K{i}"], data[f"T{i}"])
                             for i, n in enumerate(names)))


__all__ = ["CameraImage", "RGBDBundle"]
