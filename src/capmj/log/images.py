"""Camera images in episode logs: entity names, depth encoding, and the scene cameras' renders."""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np

from capmj.log.paths import CAMERA

DEPTH_MAX_MM = 65535


def image_entity(path: str, kind: str) -> str:
    """``/camera/<path>/<kind>`` for an image sent as ``recorder.image(path, ...)``."""
    p = "/".join(part for part in str(path).strip().split("/") if part)
    if p.startswith("camera/"):
        p = p[len("camera/"):]
    if not p.endswith("/" + kind) and p != kind:
        p = f"{p}/{kind}"
    return f"{CAMERA}/{p}"


def depth_mm(depth: np.ndarray) -> np.ndarray:
    """Metric depth (float metres) as uint16 millimetres: NaN -> 0, too far -> 65535."""
    d = np.asarray(depth, dtype=np.float64)
    mm = np.clip(np.nan_to_num(d * 1000.0, nan=0.0, posinf=DEPTH_MAX_MM, neginf=0.0), 0, DEPTH_MAX_MM)
    return mm.astype(np.uint16)


class SceneCameras:
    """Renders the scene cameras of a world on demand; after the first failure (no GL here) it
    stays off and remembers why, so images never fail an episode."""

    def __init__(self, world: Any, cameras: Sequence[str]) -> None:
        self.world = world
        self.cameras = tuple(cameras)
        self.error: str | None = None
        self._rig: Any = None

    def log(self, image: Callable[[str, np.ndarray], None], depth: Callable[[str, np.ndarray], None]) -> bool:
        """Render every camera and hand RGB and depth to the callbacks; False once disabled."""
        if self.error is not None:
            return False
        try:
            if self._rig is None:
                from capmj.sim.cameras import CameraRig

                self._rig = CameraRig(self.world)
            for name in self.cameras:
                fr = self._rig.render(name)
                image(f"{name}/rgb", fr.rgb)
                depth(f"{name}/depth", fr.depth)
            return True
        except Exception as exc:  # noqa: BLE001 - images are optional; never fail the episode for them
            self.error = f"{type(exc).__name__}: {exc}"
            return False

    def close(self) -> None:
        rig, self._rig = self._rig, None
        if rig is not None and hasattr(rig, "close"):
            try:
                rig.close()
            except Exception:  # noqa: BLE001
                pass


__all__ = ["DEPTH_MAX_MM", "SceneCameras", "depth_mm", "image_entity"]
