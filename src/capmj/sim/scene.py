"""Compile a tabletop scene (table, UR5e with suction, cameras, objects) with ``mujoco.MjSpec``.

The model is built per episode from a tuple of :class:`ObjectSpec`.  Building is a pure function of
the specs: the same specs give byte-identical MJCF (tested), which is what makes an episode
reproducible from (task, seed) alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import mujoco
import numpy as np

from capmj.errors import SimError
from capmj.sim.objects import (
    BALL_RADIUS,
    BLOCK_MASS,
    BOWL_FLOOR,
    BOWL_HEIGHT,
    BOWL_INNER_RADIUS,
    BOWL_RADIUS,
    FIXTURE_HEIGHT,
    FIXTURE_LONG,
    FIXTURE_SHORT,
    FIXTURE_WALL,
    ObjectSpec,
)
from capmj.sim.palette import rgba
from capmj.sim.robot import SUCTION_BODY, load_arm_spec

TIMESTEP = 0.002
WORKSPACE = np.array([[0.25, 0.75], [-0.5, 0.5], [0.0, 0.3]])
"""Ravens workspace bounds: rows x, y, z; columns min, max (metres)."""

IMAGE_W, IMAGE_H, FOCAL = 640, 480, 450.0
CAMERA_POSES: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "front": ((1.0, 0.0, 0.75), (0.5, 0.0, 0.0)),
    "left": ((0.0, 0.5, 0.75), (0.5, 0.0, 0.0)),
    "right": ((0.0, -0.5, 0.75), (0.5, 0.0, 0.0)),
}
"""Camera name -> (position, look-at point); RealSense-D415-like, as in Ravens."""
HEIGHTMAP_CAMERA = "top"
HEIGHTMAP_PIXEL = 0.003125
HEIGHTMAP_CAMERA_Z = 1.0
BOWL_WALL_SEGMENTS = 16


@dataclass(frozen=True)
class CompiledScene:
    """A compiled model plus the spec it came from (all derived from the object specs)."""

    model: mujoco.MjModel
    objects: tuple[ObjectSpec, ...]
    spec: mujoco.MjSpec

    @property
    def xml(self) -> str:
        """The scene as MJCF (computed on demand: it costs ~50 ms, as much as compiling)."""
        return self.spec.to_xml()


def _lookat_quat(pos: Sequence[float], target: Sequence[float]) -> list[float]:
    """Quaternion (w, x, y, z) of a MuJoCo camera at ``pos`` looking at ``target`` (z up)."""
    f = np.asarray(target, float) - np.asarray(pos, float)
    f /= np.linalg.norm(f)
    right = np.cross(f, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    mat = np.column_stack([right, up, -f])  # camera looks along its -z axis
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, mat.reshape(-1))
    return quat.tolist()


def _yaw_quat(yaw: float) -> list[float]:
    return [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]


def _add_world(spec: mujoco.MjSpec) -> None:
    spec.option.timestep = TIMESTEP
    spec.option.enableflags |= int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    spec.visual.global_.offwidth = IMAGE_W
    spec.visual.global_.offheight = IMAGE_H
    spec.visual.quality.offsamples = 0
    spec.visual.quality.shadowsize = 0
    spec.visual.map.znear = 0.01
    spec.visual.map.zfar = 5.0
    spec.stat.extent = 1.0
    spec.stat.center = [0.5, 0.0, 0.1]
    spec.visual.headlight.ambient = [0.35, 0.35, 0.35]
    spec.visual.headlight.diffuse = [0.45, 0.45, 0.45]
    spec.visual.headlight.specular = [0.0, 0.0, 0.0]
    for light in list(spec.lights):  # the Menagerie spotlight over-exposes the top camera
        spec.delete(light)
    wb = spec.worldbody
    wb.add_light(name="sun", type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL, pos=[0.5, 0, 2], dir=[0, 0, -1],
                 diffuse=[0.5, 0.5, 0.5], castshadow=False)
    wb.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2.0, 2.0, 0.05], rgba=[0.25, 0.25, 0.27, 1],
                friction=[1.0, 0.005, 0.0001])
    wb.add_geom(name="workspace", type=mujoco.mjtGeom.mjGEOM_BOX, pos=[0.5, 0.0, -0.0001], size=[0.25, 0.5, 0.0003],
                rgba=[0.55, 0.5, 0.45, 1], contype=0, conaffinity=0)
    for name, (pos, target) in CAMERA_POSES.items():
        fovy = math.degrees(2 * math.atan(IMAGE_H / 2 / FOCAL))
        wb.add_camera(name=name, pos=list(pos), quat=_lookat_quat(pos, target), fovy=fovy)
    # Orthographic top-down camera for the heightmap: image x = world +x, image up = world +y.
    wb.add_camera(name=HEIGHTMAP_CAMERA, pos=[0.5, 0.0, HEIGHTMAP_CAMERA_Z], quat=[1, 0, 0, 0],
                  proj=mujoco.mjtProjection.mjPROJ_ORTHOGRAPHIC, fovy=float(WORKSPACE[1, 1] - WORKSPACE[1, 0]))


def _add_object(spec: mujoco.MjSpec, obj: ObjectSpec) -> None:
    color = list(rgba(obj.color))
    body = spec.worldbody.add_body(name=obj.body, pos=list(obj.pos), quat=_yaw_quat(obj.yaw))
    box = mujoco.mjtGeom.mjGEOM_BOX
    fric = [1.0, 0.005, 0.0001]
    if obj.kind == "block":
        body.add_freejoint(name=f"{obj.body}_free")
        body.add_geom(name=f"{obj.body}_g0", type=box, size=list(obj.half_extents), rgba=color,
                      mass=BLOCK_MASS[obj.size or "small"], friction=fric)
    elif obj.kind == "zone":
        hx, hy, hz = obj.half_extents
        body.add_geom(name=f"{obj.body}_g0", type=box, size=[hx, hy, hz], rgba=color, contype=0, conaffinity=0)
    elif obj.kind == "ball":
        body.add_geom(name=f"{obj.body}_g0", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[BALL_RADIUS, 0, 0],
                      rgba=color, friction=fric)
    elif obj.kind == "bowl":
        _add_bowl(body, obj, color, fric)
    elif obj.kind == "fixture":
        _add_fixture(body, obj, color, fric)
    else:  # pragma: no cover - ObjectSpec validates kinds
        raise SimError(f"no builder for object kind {obj.kind!r}")


def _add_bowl(body: mujoco.MjsBody, obj: ObjectSpec, color: list[float], fric: list[float]) -> None:
    """A concave bowl from convex pieces: a floor disc and a ring of wall boxes.

    The centre ``obj.pos`` is mid-height; objects really fall inside because the inside is empty.
    """
    z0 = -BOWL_HEIGHT / 2
    body.add_geom(name=f"{obj.body}_g0", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                  size=[BOWL_RADIUS, BOWL_FLOOR / 2, 0], pos=[0, 0, z0 + BOWL_FLOOR / 2], rgba=color, friction=fric)
    thick = BOWL_RADIUS - BOWL_INNER_RADIUS
    r_mid = (BOWL_RADIUS + BOWL_INNER_RADIUS) / 2
    half_len = r_mid * math.tan(math.pi / BOWL_WALL_SEGMENTS) + thick / 2
    for i in range(BOWL_WALL_SEGMENTS):
        a = 2 * math.pi * i / BOWL_WALL_SEGMENTS
        body.add_geom(name=f"{obj.body}_g{i + 1}", type=mujoco.mjtGeom.mjGEOM_BOX,
                      size=[thick / 2, half_len, BOWL_HEIGHT / 2], pos=[r_mid * math.cos(a), r_mid * math.sin(a), 0],
                      quat=_yaw_quat(a), rgba=color, friction=fric)


def _add_fixture(body: mujoco.MjsBody, obj: ObjectSpec, color: list[float], fric: list[float]) -> None:
    """An L-fixture whose slot (0, 0) is the body origin; walls run along local -y and -x sides.

    Slots for blocks of edge ``a`` sit at (0,0), (a,0), (0,a) in the body frame (spec task 10).
    """
    a, t, h = 0.04, FIXTURE_WALL, FIXTURE_HEIGHT
    z = h / 2 - obj.pos[2]  # walls stand on the table whatever the body height
    body.add_geom(name=f"{obj.body}_g0", type=mujoco.mjtGeom.mjGEOM_BOX, size=[FIXTURE_LONG / 2, t / 2, h / 2],
                  pos=[-a / 2 - t + FIXTURE_LONG / 2, -a / 2 - t / 2, z], rgba=color, friction=fric)
    body.add_geom(name=f"{obj.body}_g1", type=mujoco.mjtGeom.mjGEOM_BOX, size=[t / 2, FIXTURE_SHORT / 2, h / 2],
                  pos=[-a / 2 - t / 2, -a / 2 + FIXTURE_SHORT / 2, z], rgba=color, friction=fric)


def _add_suction_welds(spec: mujoco.MjSpec, objects: Sequence[ObjectSpec]) -> None:
    """One inactive weld per movable object; the relative pose is written at activation time."""
    for obj in objects:
        if obj.fixed:
            continue
        eq = spec.add_equality(name=f"suction_{obj.body}", type=mujoco.mjtEq.mjEQ_WELD,
                               objtype=mujoco.mjtObj.mjOBJ_BODY, name1=SUCTION_BODY, name2=obj.body)
        eq.active = False
        eq.solref = [0.004, 1.0]
        # MjSpec's default data puts the anchor 1 m away; anchor 0, identity relpose, torquescale 1.
        eq.data = [0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0]


def compile_scene(objects: Sequence[ObjectSpec]) -> CompiledScene:
    """Build and compile the MuJoCo model for a scene; raises ``SimError`` with the reason."""
    ids = [o.obj_id for o in objects]
    if len(set(ids)) != len(ids):
        raise SimError(f"object ids must be unique, got {sorted(ids)}")
    spec = load_arm_spec()
    spec.modelname = "capmj_tabletop"
    _add_world(spec)
    for obj in objects:
        _add_object(spec, obj)
    _add_suction_welds(spec, objects)
    try:
        model = spec.compile()
    except Exception as exc:  # mujoco raises ValueError with the compiler message
        raise SimError(f"scene failed to compile: {exc}") from exc
    return CompiledScene(model=model, objects=tuple(objects), spec=spec)
