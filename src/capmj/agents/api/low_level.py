"""The low-level planner API (``--api low``): what a robot driver offers, one method per function.

The second surface of the planner-API wing beside :class:`~capmj.agents.api.plan_functions.PlanFunctions`:
plan code at this level gets no pick-and-place.  It reads the objects as the API sees them (the
simulator's, or the perceived detections under ``--perception rgbd``) and the raw RGB-D images
with their calibration, and drives the arm: tool poses, straight and guarded Cartesian moves,
joint-space moves, IK, suction.  :class:`LowLevelFunctions` works over the same facade
(:class:`~capmj.agents.api.planner_api.PlannerAPI` or its perceiving subclass, through
:class:`~capmj.agents.api.interface.PlannerInterface`), which resolves names and logs every call
(:meth:`PlannerAPI.functions` with ``level="low"``), in the same sandbox with the same errors; the
arm is driven through :class:`~capmj.agents.api.low_level_robot.RobotDriver` (contact watch,
budgets, records).  The docstrings are the full statement; ``prompts/planner_low.py`` documents
the same functions for the LLM.  Planned moves (``move_to_pose``, ``move_to_joints``, ``home``)
go around obstacles; straight moves (``move_linear``, ``move_through``, ``move_until_contact``) go
exactly where they are told.

Conventions: metres and radians in the world frame of the high level (robot base at the origin,
table top at z = 0); the suction tool always points straight down, so a tool pose is a position
[x, y, z] of the suction tip and a yaw about z; object quaternions are (x, y, z, w).  A move the
arm cannot make raises :class:`~capmj.errors.UnreachablePose` (or, planned, finds no clear path:
:class:`~capmj.errors.MotionPlanningError`) before it moves; a move that touches something it was
not meant to stops and raises :class:`~capmj.errors.CollisionDetected`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from capmj.agents.api.interface import PlannerInterface
from capmj.agents.api.low_level_robot import RobotDriver, as_points
from capmj.agents.api.plan_functions import PlanFunctions
from capmj.agents.api.values import is_number
from capmj.agents.api.values import summary as _summary
from capmj.sim.objects import ObjectSpec

LOW_LEVEL_FUNCTIONS: tuple[str, ...] = (
    "get_object_names",
    "get_object_pose",
    "get_object",
    "get_objects",
    "get_camera_images",
    "get_ee_pose",
    "get_joint_positions",
    "solve_ik",
    "move_to_pose",
    "move_through",
    "move_linear",
    "move_until_contact",
    "move_to_joints",
    "home",
    "suction_on",
    "suction_off",
    "is_holding",
    "say",
)
"""The names of the low-level API functions (methods of :class:`LowLevelFunctions`), in the order
:meth:`PlannerAPI.functions` returns them at ``level="low"``."""

LEVELS: tuple[str, ...] = ("high", "low")
"""The API levels (``--api``): ``high`` the pick-and-place API, ``low`` this one."""


class LowLevelFunctions:
    """The low-level API functions of one episode, one method each (module docstring)."""

    def __init__(self, api: PlannerInterface) -> None:
        self._api = api
        self._robot = RobotDriver(api, self._name_of)
        self._high = PlanFunctions(api)
        self._rig: Any = None

    def _name_of(self, sim_id: int) -> str | None:
        """The name of an object the robot touched, when the API's objects are the simulator's."""
        if getattr(self._api, "scene", None) is not None:
            return None  # perceived: the robot does not know which detection it hit
        o = self._api.world.objects_by_id.get(sim_id)
        return o.name if o is not None else None

    # ------------------------------------------------------------------ reading arguments
    @staticmethod
    def _position(value: Any, what: str = "position") -> np.ndarray:
        if isinstance(value, np.ndarray):
            value = value.tolist()
        if not (isinstance(value, (list, tuple)) and len(value) == 3 and all(is_number(v) for v in value)):
            raise ValueError(f"{what} must be [x, y, z] in metres, got {_summary(value, 80)}")
        pos = np.asarray(value, float)
        if not np.all(np.isfinite(pos)):
            raise ValueError(f"{what} {pos.tolist()} is not finite")
        return pos

    def _yaw(self, yaw: Any) -> float:
        if yaw is None:
            return self._robot.motion.commanded_yaw()
        if not is_number(yaw) or not math.isfinite(float(yaw)):
            raise ValueError(f"yaw must be an angle in radians about z (or None to keep the tool's), got "
                             f"{_summary(yaw, 80)}")
        return float(yaw)

    @staticmethod
    def _speed(speed: Any, default: float) -> float:
        if speed is None:
            return default
        if not is_number(speed) or not 0.01 <= float(speed) <= 1.5:
            raise ValueError(f"speed must be a tip speed from 0.01 to 1.5 m/s, got {_summary(speed, 80)}")
        return float(speed)

    def _info(self, o: ObjectSpec) -> dict[str, Any]:
        api = self._api
        pos = [float(v) for v in api.position(o.obj_id)]
        quat = api.quat_xyzw(o.obj_id)
        lo, hi = api.world.aabb(o.obj_id)
        return {"name": o.name, "obj_id": o.obj_id, "kind": o.kind, "color": o.color, "size": o.size,
                "fixed": o.fixed, "position": pos, "quaternion": quat,
                "yaw": 2 * math.atan2(quat[2], quat[3]), "half_size": [float(v) for v in o.half_extents],
                "bbox": [float(v) for v in (*lo, *hi)]}

    # ------------------------------------------------------------------ objects and images
    def get_object_names(self) -> list[str]:
        """Names of every object ('movable small blue block with obj_id 3'); the list `objects` holds them too."""
        return self._api.object_names()

    def get_object_pose(self, obj) -> tuple[list[float], list[float]]:
        """([x, y, z], [qx, qy, qz, qw]) of an object (a name or an int obj_id): its centre (a bowl's axis
        at mid-height of its wall; a fixture's slot (0, 0, 0) at a small block's centre height) and
        orientation.  Upright objects: yaw = 2 * atan2(qz, qw)."""
        o = self._api.resolve(obj)
        return [float(v) for v in self._api.position(o.obj_id)], self._api.quat_xyzw(o.obj_id)

    def get_object(self, obj) -> dict[str, Any]:
        """Everything the API knows of one object, as a dict: name, obj_id, kind ('block', 'zone', 'bowl',
        'ball', 'fixture'), color, size ('tiny' / 'small' / 'big' for blocks, else None), fixed (cannot
        be picked), position [x, y, z], quaternion [x, y, z, w], yaw (rad), half_size [hx, hy, hz] in its
        own frame, bbox (xmin, ymin, zmin, xmax, ymax, zmax) world axis-aligned."""
        return self._info(self._api.resolve(obj))

    def get_objects(self) -> list[dict[str, Any]]:
        """:meth:`get_object` of every object, in one call (under --perception rgbd: the perceived
        detections, perceived again after every suction_off)."""
        return [self._info(o) for o in self._api.objects()]

    def get_camera_images(self) -> dict[str, dict[str, np.ndarray]]:
        """The cameras' raw views now, by camera name ('front', 'left', 'right'): a dict with 'rgb'
        (H x W x 3 uint8), 'depth' (H x W float32 metres along the optical axis), 'intrinsics' (3 x 3:
        fx, fy, cx, cy in pixels) and 'extrinsics' (4 x 4 camera-to-world, OpenCV axes: x right, y down,
        z forward).  A pixel (u, v) at depth d is the world point extrinsics @ [(u + 0.5 - cx) d / fx,
        (v + 0.5 - cy) d / fy, d, 1]."""
        if self._rig is None:
            from capmj.sim.cameras import CameraRig

            self._rig = CameraRig(self._robot.world)
        out = {}
        for name in self._rig.camera_names:
            f = self._rig.render(name, seg=False)
            out[name] = {"rgb": np.array(f.rgb), "depth": np.array(f.depth), "intrinsics": np.array(f.intrinsics),
                         "extrinsics": np.array(f.extrinsics)}
        return out

    # ------------------------------------------------------------------ the arm
    def get_ee_pose(self) -> tuple[list[float], float]:
        """([x, y, z], yaw) of the suction tip now (the tool points straight down; yaw in rad about z)."""
        pos, yaw = self._robot.tool_pose()
        return [float(v) for v in pos], float(yaw)

    def get_joint_positions(self) -> list[float]:
        """The six arm joints now (rad): shoulder pan, shoulder lift, elbow, wrist 1, 2, 3."""
        return [float(v) for v in self._robot.joints()]

    def solve_ik(self, position, yaw=None) -> list[float]:
        """Joints (6, rad) that put the suction tip at ``position`` [x, y, z] pointing down with ``yaw``
        (None: the tool's yaw now), nearest the joints now.  Raises UnreachablePose when there is none."""
        return [float(v) for v in self._robot.ik(self._position(position), self._yaw(yaw))]

    def move_to_pose(self, position, yaw=None) -> None:
        """Move the suction tip to ``position`` [x, y, z] with ``yaw`` (None: keep it) on a planned path
        clear of the objects (up above everything on the table, carried object included, across, then
        straight down; a leg with something in its way is planned around it).  Raises UnreachablePose or
        MotionPlanningError (no clear path) before the arm moves, CollisionDetected when it stopped."""
        self._robot.move_planned("move_to_pose", self._position(position), self._yaw(yaw))

    def move_through(self, waypoints, yaw=None) -> None:
        """Move the suction tip along straight lines through ``waypoints`` in turn: each [x, y, z] (keeping
        the yaw before it; ``yaw`` for the first, None: the tool's) or ([x, y, z], yaw).  Every line is
        checked before the arm moves (UnreachablePose); a contact on the way raises CollisionDetected."""
        if not isinstance(waypoints, (list, tuple)) or not waypoints:
            raise ValueError(f"waypoints must be a non-empty list of [x, y, z] or ([x, y, z], yaw), got "
                             f"{_summary(waypoints, 80)}")
        points = as_points(waypoints, self._yaw(yaw), lambda p: self._position(p, "a waypoint"))
        self._robot.move_lines("move_through", points)

    def move_linear(self, position, yaw=None, speed=None) -> None:
        """Move the suction tip in a straight line to ``position`` [x, y, z] with ``yaw`` (None: keep it), at
        ``speed`` m/s (None: full speed, 1.2).  A contact on the way stops the arm and raises
        CollisionDetected: to go down onto something, use move_until_contact."""
        robot = self._robot
        robot.move_lines("move_linear", [(self._position(position), self._yaw(yaw))],
                         self._speed(speed, robot.motion.cfg.speed))

    def move_until_contact(self, position, yaw=None, speed=None) -> bool:
        """A guarded move: the suction tip in a straight line towards ``position`` [x, y, z] (it may lie up to
        5 cm below the table top), stopping at the first contact of the tool (the cup; the carried object
        when one is held), at ``speed`` m/s (None: 0.25).  Returns True when it stopped on contact, False when
        it reached ``position`` touching nothing.  Any other contact (an arm link) raises CollisionDetected."""
        robot = self._robot
        return robot.move_until_contact("move_until_contact", self._position(position), self._yaw(yaw),
                                        self._speed(speed, robot.motion.cfg.approach_speed))

    def move_to_joints(self, joints) -> None:
        """Move in joint space to ``joints`` (6 angles, rad), every joint starting and stopping together
        (planned around what is in the way when the straight joint path is not clear).  Raises
        UnreachablePose for a joint beyond its limit or a tool below the table, MotionPlanningError when
        no clear path exists, CollisionDetected for a contact on the way."""
        if isinstance(joints, np.ndarray):
            joints = joints.tolist()
        if not (isinstance(joints, (list, tuple)) and len(joints) == 6 and all(is_number(v) for v in joints)):
            raise ValueError(f"joints must be 6 angles in radians, got {_summary(joints, 80)}")
        self._robot.move_joints("move_to_joints", np.asarray(joints, float))

    def home(self) -> None:
        """Move in joint space (planned, as :meth:`move_to_joints`) to the home joints: the arm folded
        over the rear of its base, out of the cameras' view."""
        self._robot.home("home")

    def suction_on(self) -> bool:
        """Switch the suction on.  It grips the movable object the cup touches now (fixed objects cannot
        be gripped); returns whether it holds something.  Touching nothing, it holds nothing."""
        return self._robot.suction_on()

    def suction_off(self) -> None:
        """Switch the suction off: whatever it held is let go where it is."""
        self._robot.suction_off()

    def is_holding(self) -> bool:
        """Whether the suction holds an object now."""
        return self._robot.holding()

    def say(self, msg) -> None:
        """Record a message in the episode log (capped like the high level's ``say``)."""
        self._high.say(msg)


__all__ = ["LEVELS", "LOW_LEVEL_FUNCTIONS", "LowLevelFunctions"]
