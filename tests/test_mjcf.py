"""The world's MJCF files: each one loads on its own, and the constants the code uses agree with them."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from capmj.resources import mjcf_path, packaged
from capmj.sim import objects as O
from capmj.sim.bounds import WORKSPACE
from capmj.sim.cameras import VIEW_CAMERAS
from capmj.sim.pose import (from_frame_2d, lookat_quat, mat_yaw, quat_euler_xyz, quat_to_mat, quat_yaw, rotate_2d,
                            to_frame_2d, wxyz, xyzw, yaw_quat)
from capmj.sim.robot import CUP_LENGTH, CUP_RADIUS
from capmj.sim.scene import compile_scene

FILES = ("table.xml", "suction.xml", "block.xml", "zone.xml", "bowl.xml", "ball.xml", "fixture.xml")


def test_every_file_is_shipped_and_compiles_alone():
    assert sorted(p.name for p in packaged("mjcf").glob("*.xml")) == sorted(FILES)
    for name in FILES:  # what `python -m mujoco.viewer --mjcf=mjcf/<name>` opens
        model = mujoco.MjSpec.from_file(str(mjcf_path(name))).compile()
        assert model.ngeom >= 1, name


def _geoms(name: str) -> dict[str, mujoco.MjsGeom]:
    return {g.name: g for g in mujoco.MjSpec.from_file(str(mjcf_path(name))).geoms}


def test_code_constants_match_the_files():
    cup = _geoms("suction.xml")["cup"]
    assert cup.size[0] == CUP_RADIUS and cup.pos[2] + cup.size[1] == pytest.approx(CUP_LENGTH)
    bowl = _geoms("bowl.xml")
    assert bowl["g0"].size[0] == O.BOWL_RADIUS and 2 * bowl["g0"].size[1] == O.BOWL_FLOOR
    walls = [g for n, g in bowl.items() if n != "g0"]
    assert len(walls) == 16
    for g in walls:
        r = math.hypot(g.pos[0], g.pos[1])
        assert r - g.size[0] == pytest.approx(O.BOWL_INNER_RADIUS) and r + g.size[0] == pytest.approx(O.BOWL_RADIUS)
        assert 2 * g.size[2] == pytest.approx(O.BOWL_HEIGHT)
    fixture = _geoms("fixture.xml")
    assert sorted(2 * max(g.size[:2]) for g in fixture.values()) == [O.FIXTURE_SHORT, O.FIXTURE_LONG]
    assert all(2 * g.size[2] == O.FIXTURE_HEIGHT and 2 * min(g.size[:2]) == O.FIXTURE_WALL for g in fixture.values())
    # the walls' inner faces keep FIXTURE_CLEARANCE from the footprints of the slots (0,0), (a,0), (0,a)
    long_wall, short_wall = fixture["g0"], fixture["g1"]
    a = O.BLOCK_SIZES["small"]
    assert long_wall.pos[1] + long_wall.size[1] == pytest.approx(-a / 2 - O.FIXTURE_CLEARANCE)
    assert short_wall.pos[0] + short_wall.size[0] == pytest.approx(-a / 2 - O.FIXTURE_CLEARANCE)
    assert long_wall.pos[0] + long_wall.size[0] >= 1.5 * a and short_wall.pos[1] + short_wall.size[1] >= a / 2
    assert _geoms("ball.xml")["g0"].size[0] == O.BALL_RADIUS
    assert 2 * _geoms("block.xml")["g0"].size[0] == O.BLOCK_SIZES["small"]
    zone = _geoms("zone.xml")["g0"]
    assert 2 * zone.size[0] == O.ZONE_SIZE and 2 * zone.size[2] == O.ZONE_HEIGHT
    table = _geoms("table.xml")["workspace"]
    assert (table.pos[0] - table.size[0], table.pos[0] + table.size[0]) == (WORKSPACE.xmin, WORKSPACE.xmax)
    assert (table.pos[1] - table.size[1], table.pos[1] + table.size[1]) == (WORKSPACE.ymin, WORKSPACE.ymax)


def test_perspective_cameras_look_at_the_table_centre():
    spec = mujoco.MjSpec.from_file(str(mjcf_path("table.xml")))
    views = [c for c in spec.cameras if c.proj == mujoco.mjtProjection.mjPROJ_PERSPECTIVE]
    assert tuple(c.name for c in views) == VIEW_CAMERAS
    for cam in views:
        np.testing.assert_allclose(cam.quat, lookat_quat(cam.pos, WORKSPACE.center + (0.0,)), atol=1e-15)
        assert cam.fovy == pytest.approx(math.degrees(2 * math.atan(240 / 450)))


def test_composed_scene_names_and_per_object_values():
    specs = (O.ObjectSpec(1, "block", "red", (0.5, 0.1, 0.03), yaw=0.3, size="big"),
             O.ObjectSpec(2, "zone", "blue", (0.4, -0.2, 0.0005), scale=1.5),
             O.ObjectSpec(3, "fixture", "green", (0.6, 0.2, 0.05)),
             O.ObjectSpec(4, "bowl", "yellow", (0.6, -0.2, O.BOWL_HEIGHT / 2)))
    model = compile_scene(specs).model
    assert model.body("obj1").id > model.body("suction").id
    g = model.geom("obj1_g0")
    assert tuple(model.geom_size[g.id]) == (0.03, 0.03, 0.03) and model.body_mass[model.body("obj1").id] == O.BLOCK_MASS["big"]
    assert model.joint("obj1_free").type == mujoco.mjtJoint.mjJNT_FREE
    assert model.geom_size[model.geom("obj2_g0").id][0] == pytest.approx(O.ZONE_SIZE * 1.5 / 2)
    # fixture walls stand on the table although the body is 5 cm up
    assert model.geom_pos[model.geom("obj3_g0").id][2] == pytest.approx(O.FIXTURE_HEIGHT / 2 - 0.05)
    assert model.nbody == 1 + 8 + len(specs) and model.geom("obj4_g16").id > 0
    assert {model.camera(i).name for i in range(model.ncam)} == {"front", "left", "right", "top"}
    assert model.opt.timestep == 0.002 and model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST


@pytest.mark.parametrize("yaw", [-3.0, -0.4, 0.0, 1.2, 2.9])
def test_pose_helpers_agree(yaw):
    mat = quat_to_mat(yaw_quat(yaw))
    assert mat_yaw(mat) == pytest.approx(yaw)
    np.testing.assert_allclose(rotate_2d([[1.0, 0.0], [0.3, -0.2]], yaw), [mat[:2, 0], mat[:2, :2] @ [0.3, -0.2]],
                               atol=1e-15)


@pytest.mark.parametrize("yaw", [-3.0, -0.4, 0.0, 1.2, 2.9])
def test_planar_frames_and_quaternion_orders(yaw):
    q = yaw_quat(yaw)
    assert quat_yaw(q) == pytest.approx(yaw) and quat_euler_xyz(q) == pytest.approx([0.0, 0.0, yaw])
    assert wxyz(xyzw(q)) == tuple(q) and xyzw(q) == (q[1], q[2], q[3], q[0])
    origin, uv = (0.4, -0.1), np.array([[0.03, 0.0], [-0.01, 0.02]])
    world = from_frame_2d(uv, yaw, origin)
    np.testing.assert_allclose(world, origin + rotate_2d(uv, yaw), atol=1e-15)
    np.testing.assert_allclose(to_frame_2d(world, yaw, origin), uv, atol=1e-15)


def test_euler_of_a_tilted_quaternion():
    # 90° about x then 30° about z (extrinsic XYZ): PyBullet's getEulerFromQuaternion gives (π/2, 0, π/6)
    rx, rz = np.empty(4), np.empty(4)
    mujoco.mju_axisAngle2Quat(rx, [1.0, 0.0, 0.0], np.pi / 2)
    mujoco.mju_axisAngle2Quat(rz, [0.0, 0.0, 1.0], np.pi / 6)
    q = np.empty(4)
    mujoco.mju_mulQuat(q, rz, rx)
    assert quat_euler_xyz(q) == pytest.approx([np.pi / 2, 0.0, np.pi / 6], abs=1e-12)
