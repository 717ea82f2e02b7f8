"""Perception: what the robot knows of the table from its cameras alone.

The layer sits between :mod:`capmj.sim` and :mod:`capmj.agents`.  Its input is an
:class:`~capmj.perception.rgbd.RGBDBundle` (RGB, metric depth, intrinsics and extrinsics of each
camera, nothing else); its output is a tuple of :class:`~capmj.perception.detect.Detection`.  It
imports no MuJoCo and no world (``tests/test_perception.py`` checks), only the object catalogue,
the palette and the workspace bounds of :mod:`capmj.sim`, which are the robot's prior knowledge,
not an episode's state.
"""

from capmj.perception.detect import Detection
from capmj.perception.perceiver import ClassicalPerceiver, Perceiver
from capmj.perception.rgbd import CameraImage, RGBDBundle

__all__ = ["CameraImage", "ClassicalPerceiver", "Detection", "Perceiver", "RGBDBundle"]
