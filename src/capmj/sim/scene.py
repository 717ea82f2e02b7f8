"""Compose a tabletop scene (table, UR5e with suction, cameras, objects) from ``mjcf/`` with ``MjSpec``.

The world's MJCF lives in files (the top-level ``mjcf/`` folder, shipped as package data):
the Menagerie UR5e with ``suction.xml`` at its flange (:mod:`capmj.sim.robot`) is the root; it
takes the options, rendering settings and statistic of ``table.xml`` and the contents of its
``table`` frame (light, floor, workspace, cameras); then one copy of an
object template (``block.xml``, ``zone.xml``, ``bowl.xml``, ``ball.xml``, ``fixture.xml``) per
:class:`ObjectSpec`, with the per-object values set on the copy: name, pose, colour, block size and
mass, zone scale, fixture height.  The model is built per episode from a tuple of specs and building
is a pure function of them: the same specs give byte-identical MJCF (tested), which is what makes an
episode reproducible from (task, seed) alone.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import mujoco

from capmj.errors import SimError
from capmj.sim.mjcf import attach_body, attach_frame_contents, load
from capmj.sim.objects import BLOCK_MASS, FIXTURE_HEIGHT, ObjectSpec
from capmj.sim.palette import rgba
from capmj.sim.pose import yaw_quat
from capmj.sim.robot import SUCTION_BODY, load_arm_spec

HEIGHTMAP_CAMERA = "top"
"""The orthographic top-down camera of ``mjcf/table.xml`` (spans the workspace's width)."""
HEIGHTMAP_PIXEL = 0.003125

__all__ = ["HEIGHTMAP_CAMERA", "HEIGHTMAP_PIXEL", "CompiledScene", "camera_view", "compile_scene"]


def camera_view(name: str) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(position, look-at point on the table plane z = 0) of a perspective camera of
    ``mjcf/table.xml``: what a viewer needs to look at the scene like that camera does."""
    cam = load("table.xml").compile().camera(name)
    pos = cam.pos.copy()
    forward = -cam.mat0.reshape(3, 3)[:, 2]  # MuJoCo cameras look along their -z axis
    if forward[2] >= 0:
        raise SimError(f"camera {name!r} does not look down at the table")
    t = -pos[2] / forward[2]
    target = pos + t * forward
    return (float(pos[0]), float(pos[1]), float(pos[2])), (float(target[0]), float(target[1]), float(target[2]))


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


def _add_object(spec: mujoco.MjSpec, obj: ObjectSpec) -> None:
    """Attach a copy of the object's template (body ``<kind>``, geoms ``g0``…) as body ``obj<N>``."""
    body = attach_body(spec.worldbody, load(f"{obj.kind}.xml"), obj.kind, f"{obj.body}_", obj.body)
    body.pos = list(obj.pos)
    body.quat = yaw_quat(obj.yaw)
    geoms = list(body.geoms)
    color = list(rgba(obj.color))
    for geom in geoms:
        geom.rgba = color
    if obj.kind == "block":
        geoms[0].size = list(obj.half_extents)
        geoms[0].mass = BLOCK_MASS[obj.size or "small"]
    elif obj.kind == "zone":
        geoms[0].size = list(obj.half_extents)
    elif obj.kind == "fixture":  # the walls stand on the table whatever the body height
        for geom in geoms:
            geom.pos[2] += FIXTURE_HEIGHT / 2 - obj.pos[2]


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
    table = load("table.xml")
    spec.modelname = table.modelname
    spec.option, spec.visual, spec.stat = table.option, table.visual, table.stat
    attach_frame_contents(spec, table, "table")
    for obj in objects:
        _add_object(spec, obj)
    _add_suction_welds(spec, objects)
    try:
        model = spec.compile()
    except Exception as exc:  # mujoco raises ValueError with the compiler message
        raise SimError(f"scene failed to compile: {exc}") from exc
    return CompiledScene(model=model, objects=tuple(objects), spec=spec)
