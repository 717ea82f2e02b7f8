"""What the planner prompt and the API docstrings promise a planner about placing precisely.

Each test backs one statement of ``prompts/planner.py`` and of ``PlanFunctions`` docstrings
(``get_obj_pos``, ``get_obj_rot``, ``get_bbox``, ``put_first_on_second``): objects start at
random yaws; the yaw an object ends with for each target form; what z means in ``[x, y, z]``;
what ``get_obj_pos`` returns per kind; what ``get_bbox`` of a turned zone or a bowl is.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from capmj.agents.api.planner_api import PlannerAPI
from capmj.sim.objects import BLOCK_SIZES, BOWL_HEIGHT, BOWL_RADIUS, FIXTURE_CLEARANCE, FIXTURE_HEIGHT, ObjectSpec
from capmj.sim.world import World
from capmj.tasks import predicates as P
from capmj.tasks.protocol import make_scene
from capmj.tasks.registry import get_task
from test_api import make_ctx

QUARTER = math.pi / 2


def block_yaw_error(yaw: float, want: float) -> float:
    """|yaw − want| modulo the 90° symmetry of a cube (rad)."""
    return abs((yaw - want + QUARTER / 2) % QUARTER - QUARTER / 2)


def scene() -> list[ObjectSpec]:
    return [
        ObjectSpec(1, "zone", "green", (0.45, 0.2, 0.0005), yaw=0.5),
        ObjectSpec(2, "bowl", "blue", (0.6, -0.25, 0.0175), yaw=0.7),
        ObjectSpec(3, "block", "red", (0.4, -0.1, 0.02), yaw=0.6, size="small"),
        ObjectSpec(4, "block", "yellow", (0.6, 0.1, 0.02), yaw=0.35, size="small"),
        ObjectSpec(5, "block", "purple", (0.35, 0.35, 0.02), yaw=1.0, size="small"),
        ObjectSpec(6, "fixture", "white", (0.6, 0.3, 0.02), yaw=2.2),
        ObjectSpec(7, "ball", "pink", (0.35, -0.3, 0.03)),
    ]


@pytest.fixture()
def api():
    ctx = make_ctx(scene())
    fns = PlannerAPI(ctx).functions()
    names = {o.obj_id: o.name for o in ctx.world.objects}
    return fns, names, ctx


def test_objects_start_at_random_yaws():
    """'Objects start at random yaws': the blocks of real task scenes are turned, and not alike."""
    task = get_task("build-cube")
    yaws = []
    for seed in (10001, 10003, 10005):
        s = make_scene(task, seed)
        w = World(s.objects)
        yaws += [block_yaw_error(w.pose(o.obj_id).yaw, 0.0) for o in s.objects if o.kind == "block"]
    assert max(yaws) > math.radians(30) and np.std(yaws) > math.radians(8)


@pytest.mark.parametrize("target", [[0.5, -0.2], [0.5, -0.2, 0.02], ([0.5, -0.2], None)])
def test_bare_position_places_world_aligned(api, target):
    """[x, y] and [x, y, z] end at yaw 0 (the pose (position, (0, 0, 0, 1))), whatever the start yaw."""
    f, names, ctx = api
    if isinstance(target, tuple):  # the identity quaternion says the same thing explicitly
        target = (target[0], [0.0, 0.0, 0.0, 1.0])
    start = ctx.world.pose(3).yaw
    assert block_yaw_error(start, 0.0) > math.radians(30)
    f["put_first_on_second"](names[3], target)
    pose = ctx.world.pose(3)
    assert np.allclose(pose.pos[:2], [0.5, -0.2], atol=0.005)
    assert block_yaw_error(pose.yaw, 0.0) < math.radians(2)


def test_pose_target_turns_to_its_yaw(api):
    f, names, ctx = api
    yaw = 0.4
    f["put_first_on_second"](names[3], ([0.5, -0.2, 0.02], [0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)]))
    assert block_yaw_error(ctx.world.pose(3).yaw, yaw) < math.radians(2)


def test_name_target_turns_like_the_block_or_zone_below(api):
    f, names, ctx = api
    f["put_first_on_second"](names[3], names[1])       # on the zone: turned like the zone
    zone_yaw = ctx.world.pose(1).yaw
    assert block_yaw_error(ctx.world.pose(3).yaw, zone_yaw) < math.radians(2)
    f["put_first_on_second"](names[5], names[4])       # on a block: turned like that block
    assert block_yaw_error(ctx.world.pose(5).yaw, ctx.world.pose(4).yaw) < math.radians(2)


def test_in_a_bowl_a_block_keeps_its_yaw(api):
    f, names, ctx = api
    start = ctx.world.pose(4).yaw
    f["put_first_on_second"](names[4], names[2])
    assert P.in_bowl(ctx.world.state(), 4, 2)
    assert block_yaw_error(ctx.world.pose(4).yaw, start) < math.radians(5)
    assert block_yaw_error(ctx.world.pose(4).yaw, ctx.world.pose(2).yaw) > math.radians(10)


def test_z_is_the_centre_height_where_the_object_is_let_go(api):
    """z below the resting height counts as resting; z above it drops the object onto what is there;
    z over a block rests on the block."""
    f, names, ctx = api
    half = BLOCK_SIZES["small"] / 2
    f["put_first_on_second"](names[3], [0.5, -0.2, 0.0])  # below the table: rests on it
    assert ctx.world.pose(3).pos[2] == pytest.approx(half, abs=0.002)
    f["put_first_on_second"](names[4], [0.5, 0.0, 0.09])  # in the air: let go there, falls to the table
    assert ctx.world.pose(4).pos[2] == pytest.approx(half, abs=0.002)
    assert ctx.world.pose(4).tilt < math.radians(5)
    f["put_first_on_second"](names[5], [0.5, -0.2, 3 * half])  # the top of the red block
    assert P.resting_on(ctx.world.state(), 5, 3)
    assert ctx.world.pose(5).pos[2] == pytest.approx(3 * half, abs=0.003)


def test_get_obj_pos_per_kind(api):
    f, names, ctx = api
    for oid in (3, 7):  # block, ball: the geometric centre
        lo, hi = ctx.world.aabb(oid)
        assert np.allclose(f["get_obj_pos"](names[oid]), (np.asarray(lo) + np.asarray(hi)) / 2, atol=1e-3)
    assert f["get_obj_pos"](names[1]) == pytest.approx([0.45, 0.2, 0.0005], abs=1e-4)     # zone: its centre
    assert f["get_obj_pos"](names[2]) == pytest.approx([0.6, -0.25, BOWL_HEIGHT / 2], abs=1e-4)  # bowl: mid-height
    # fixture: the origin of its local frame = the centre of a small block standing in slot (0, 0, 0)
    x, y, z = f["get_obj_pos"](names[6])
    assert (x, y, z) == pytest.approx((0.6, 0.3, FIXTURE_HEIGHT / 2), abs=1e-4)
    lo, hi = ctx.world.aabb(6)
    assert math.hypot(x - (lo[0] + hi[0]) / 2, y - (lo[1] + hi[1]) / 2) > 0.015  # not the middle of the L


def test_fixture_slots_from_the_reported_frame_hold_blocks(api):
    """Blocks put at (0,0), (a,0), (0,a) of get_obj_pos / get_obj_rot of a fixture, turned like it,
    end in their slots, clear of the walls (FIXTURE_CLEARANCE)."""
    f, names, ctx = api
    a = BLOCK_SIZES["small"]
    x, y, _ = f["get_obj_pos"](names[6])
    q = f["get_obj_rot"](names[6])
    yaw = 2 * math.atan2(q[2], q[3])
    c, s = math.cos(yaw), math.sin(yaw)
    slots = [(0.0, 0.0), (a, 0.0), (0.0, a)]
    for oid, (u, v) in zip((3, 4, 5), slots):
        f["put_first_on_second"](names[oid], ([x + c * u - s * v, y + s * u + c * v], q))
    state = ctx.world.state()
    assert P.slot_occupants(state, 6, [3, 4, 5]) == [3, 4, 5]
    # slot (0,0) lies between the walls only: it lands to a millimetre; the other two slots touch
    # their neighbour (the stated slots are exactly a apart) and land within the slot tolerance
    d = [float(np.linalg.norm(state.pos(oid) - c)) for oid, c in zip((3, 4, 5), P.fixture_slots(state.pos(6), state.poses[6].yaw))]
    assert d[0] < 0.002 and max(d) < P.SLOT_TOL
    assert FIXTURE_CLEARANCE > 0


def test_get_bbox_of_a_turned_zone_and_of_a_bowl(api):
    f, names, ctx = api
    xmin, ymin, _, xmax, ymax, _ = f["get_bbox"](names[1])
    q = f["get_obj_rot"](names[1])
    t = 2 * math.atan2(q[2], q[3])
    assert t == pytest.approx(0.5, abs=1e-3)  # 'yaw = 2 * math.atan2(q[2], q[3])'
    spread = abs(math.cos(t)) + abs(math.sin(t))
    assert xmax - xmin == pytest.approx(0.12 * spread, abs=1e-4) and ymax - ymin == pytest.approx(0.12 * spread, abs=1e-4)
    assert (xmax - xmin) / spread == pytest.approx(0.12, abs=1e-4)  # the side, as the prompt says to recover it
    bxmin, bymin, _, bxmax, bymax, _ = f["get_bbox"](names[2])  # a bowl turned by 0.7 rad: its disc's box
    assert (bxmax - bxmin, bymax - bymin) == pytest.approx((2 * BOWL_RADIUS, 2 * BOWL_RADIUS), abs=1e-6)


def test_reporter_in_zone_is_the_tasks_rule():
    """The text reporter's pre-bound in_zone applies predicates.in_zone's rule (yaw and scale of the
    zone honoured), not an axis-aligned 0.06 m box: one meaning of "in the zone"."""
    from capmj.agents.report.text_env import reporter_env

    objs = [ObjectSpec(1, "zone", "green", (0.5, 0.0, 0.0005), yaw=math.pi / 4),
            ObjectSpec(2, "zone", "red", (0.5, 0.3, 0.0005), scale=2.0),
            ObjectSpec(3, "block", "blue", (0.575, 0.0, 0.02), size="small"),  # along the turned zone's diagonal: in
            ObjectSpec(4, "block", "yellow", (0.55, 0.05, 0.02), size="small"),  # in the axis box, out of the turned square
            ObjectSpec(5, "block", "pink", (0.59, 0.39, 0.02), size="small")]  # in the 2x zone only
    ctx = make_ctx(objs)
    env = reporter_env(PlannerAPI(ctx).functions(), ctx.world.objects, "test")
    state = ctx.world.state()
    names = {o.obj_id: o.name for o in ctx.world.objects}
    seen = []
    for b in (3, 4, 5):
        for z in (1, 2):
            assert env["in_zone"](names[b], names[z]) == P.in_zone(state, b, z), (b, z)
            seen.append(P.in_zone(state, b, z))
    assert seen == [True, False, False, False, False, True]
    with pytest.raises(ValueError, match="not a zone"):
        env["in_zone"](names[3], names[4])
    # CapRavens' checking code reads the poses as object_positions
    assert env["object_positions"] is env["poses"] and env["object_positions"][names[3]][0] == pytest.approx([0.575, 0.0, 0.02], abs=2e-3)
