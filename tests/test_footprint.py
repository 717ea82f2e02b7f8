"""The one footprint model (capmj.sim.footprint) against compiled MuJoCo geometry, and its users.

The planner API and the success predicates both measure footprints with it; these tests check
that the model covers what the compiled geoms cover, that its tilt limit is the judge's, and that
the planner and the judge now answer alike for the same object (they used to differ for objects
tilted between 15° and 20° and for fixtures).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from shapely.geometry import Polygon

from capmj.agents.api.footprints import Footprints
from capmj.sim import footprint as F
from capmj.sim.objects import BALL_RADIUS, BOWL_RADIUS, ObjectSpec
from capmj.sim.pose import from_frame_2d, mat_yaw
from capmj.sim.shapes import FIXTURE_WALLS
from capmj.sim.world import World
from capmj.tasks import predicates as P

SPECS = (
    ObjectSpec(1, "block", "red", (0.45, -0.15, 0.03), yaw=0.4, size="big"),
    ObjectSpec(2, "zone", "blue", (0.5, 0.2, 0.0005), yaw=-0.7, scale=1.5),
    ObjectSpec(3, "fixture", "green", (0.62, -0.05, 0.02), yaw=2.2),
    ObjectSpec(4, "bowl", "yellow", (0.35, 0.1, 0.0175), yaw=0.3),
    ObjectSpec(5, "ball", "purple", (0.65, 0.3, 0.03)),
    ObjectSpec(6, "block", "orange", (0.3, -0.35, 0.02), yaw=-0.2, size="small"),
)


def _world() -> World:
    world = World(SPECS)
    world.settle()
    return world


def _tilt(world: World, obj_id: int, angle: float, axis=(1.0, 0.3, 0.0)) -> None:
    """Turn a movable object about a horizontal axis in place (no physics step)."""
    m, d = world.model, world.data
    adr = m.jnt_qposadr[m.joint(f"obj{obj_id}_free").id]
    turn = np.zeros(4)
    mujoco.mju_axisAngle2Quat(turn, np.asarray(axis, float) / np.linalg.norm(axis), angle)
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, turn, d.qpos[adr + 3:adr + 7].copy())
    d.qpos[adr + 3:adr + 7] = out
    mujoco.mj_forward(m, d)


def _geom_rects(world: World, obj_id: int) -> list[Polygon]:
    """The xy rectangles of an object's box geoms as compiled (what the planner used to read)."""
    m, d = world.model, world.data
    out = []
    for g in np.flatnonzero(world.geom_obj == obj_id):
        mat = d.geom_xmat[g].reshape(3, 3)
        c = d.geom_xpos[g] + mat @ m.geom_aabb[g, :3]
        hx, hy = m.geom_aabb[g, 3:5]
        out.append(Polygon(from_frame_2d([(hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)], mat_yaw(mat), c[:2])))
    return out


def test_fixture_walls_are_the_geoms_the_file_compiles() -> None:
    world = _world()
    m = world.model
    geoms = np.flatnonzero(world.geom_obj == 3)
    assert len(geoms) == len(FIXTURE_WALLS) == 2
    for g, wall in zip(geoms, FIXTURE_WALLS):
        np.testing.assert_allclose(m.geom_pos[g][:2], wall.centre[:2], atol=1e-12)
        np.testing.assert_allclose(m.geom_size[g], wall.half, atol=1e-12)


@pytest.mark.parametrize("obj_id", [1, 2, 3, 6])
def test_upright_footprint_covers_exactly_the_compiled_geoms(obj_id: int) -> None:
    world = _world()
    o = world.objects_by_id[obj_id]
    model = F.shape(o, world.pose(obj_id))
    geoms = _geom_rects(world, obj_id)
    union = geoms[0].union(geoms[1]) if len(geoms) == 2 else geoms[0]
    assert model.symmetric_difference(union).area < 1e-12
    assert model.area == pytest.approx(sum(g.area for g in geoms))


def test_round_kinds_are_discs_of_the_rim_and_the_ball() -> None:
    world = _world()
    bowl, ball = (F.parts(world.objects_by_id[i], world.pose(i)) for i in (4, 5))
    assert bowl == [F.Disc(*world.pose(4).pos[:2], BOWL_RADIUS)]
    assert ball == [F.Disc(*world.pose(5).pos[:2], BALL_RADIUS)]
    # the bowl's floor disc is its widest geom: the model's disc is the compiled outline
    g0 = world.model.geom("obj4_g0").id
    assert world.model.geom_size[g0][0] == BOWL_RADIUS


def test_beyond_the_tilt_limit_the_footprint_is_the_world_box_of_the_geoms() -> None:
    world = _world()
    o = world.objects_by_id[1]
    _tilt(world, 1, F.TILT_TOL - math.radians(1))
    assert world.pose(1).tilt < F.TILT_TOL
    upright = F.parts(o, world.pose(1))
    assert len(upright) == 1 and isinstance(upright[0], F.Rect) and upright[0].hx == o.half_extents[0]
    _tilt(world, 1, math.radians(3))
    pose = world.pose(1)
    assert F.TILT_TOL < pose.tilt < math.radians(20)  # the planner used to keep the face rectangle here
    (box,) = F.parts(o, pose)
    lo, hi = world.aabb(1)  # MuJoCo's own world box of the block's geom
    assert isinstance(box, F.Rect) and box.yaw == 0.0
    assert (box.cx - box.hx, box.cy - box.hy) == pytest.approx((lo[0], lo[1]), abs=1e-12)
    assert (box.cx + box.hx, box.cy + box.hy) == pytest.approx((hi[0], hi[1]), abs=1e-12)
    assert box.hx > o.half_extents[0]  # the tilted cube covers more than its face


@pytest.mark.parametrize("tilt_deg", [0.0, 17.0, 40.0])
def test_planner_and_judge_measure_the_same_footprint(tilt_deg: float) -> None:
    world = _world()
    if tilt_deg:
        _tilt(world, 6, math.radians(tilt_deg))
    planner = Footprints.from_world(world)
    state = world.state()
    for o in world.objects:
        judged = P.footprint(state, o.obj_id)
        assert planner.polygon(o).symmetric_difference(judged).area < 1e-12, o.name
    assert P.toppled(state, 6) == (tilt_deg > math.degrees(F.TILT_TOL))


def test_one_tilt_limit_with_the_spec_value() -> None:
    assert P.TILT_TOL is F.TILT_TOL
    assert math.degrees(F.TILT_TOL) == pytest.approx(15.0)  # spec: "none tilted more than 15°"
