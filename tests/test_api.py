"""The planner API on real worlds: names, poses, boxes, free positions and real pick-and-place."""

from __future__ import annotations

import math
from types import SimpleNamespace

import mujoco
import numpy as np
import pytest
from shapely.geometry import Point, Polygon

from capmj.agents.api.footprints import FREE_CLEARANCE
from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.base import EpisodeContext
from capmj.agents.sandbox import run_code
from capmj.errors import PlanError
from capmj.sim.objects import ObjectSpec
from capmj.sim.world import World
from capmj.tasks import predicates as P
from capmj.tasks.protocol import Scene

YAW = math.pi / 5


def make_ctx(objects, seed: int = 7) -> EpisodeContext:
    scene = Scene(tuple(objects), "test scene")
    world = World(scene.objects)
    world.settle()
    return EpisodeContext(SimpleNamespace(name="api-test"), seed, scene, world)


def table_scene() -> list[ObjectSpec]:
    return [
        ObjectSpec(1, "zone", "green", (0.45, 0.2, 0.0005), yaw=0.3),
        ObjectSpec(2, "bowl", "blue", (0.6, -0.25, 0.0175)),
        ObjectSpec(3, "block", "red", (0.4, -0.1, 0.02), yaw=YAW, size="small"),
        ObjectSpec(4, "block", "yellow", (0.6, 0.1, 0.03), yaw=0.1, size="big"),
        ObjectSpec(5, "block", "purple", (0.35, 0.35, 0.02), yaw=1.0, size="small"),
    ]


@pytest.fixture()
def api_ctx():
    ctx = make_ctx(table_scene())
    api = PlannerAPI(ctx)
    return api, api.functions(), ctx


def name_of(ctx, obj_id: int) -> str:
    return ctx.world.objects_by_id[obj_id].name


# ------------------------------------------------------------------------------------ names
def test_names_unique_live_and_listed(api_ctx):
    api, f, ctx = api_ctx
    names = f["get_obj_names"]()
    assert names == [o.name for o in ctx.world.objects]
    assert len(set(names)) == len(names) == 5
    assert "movable small red block with obj_id 3" in names
    assert "fixed green zone with obj_id 1" in names
    assert api.objects_text() == f"objects = {names!r}"
    # names are read from the live world on every call, never cached
    ctx.world.objects = ctx.world.objects[:-1]
    assert f["get_obj_names"]() == names[:-1]


def test_unknown_name_is_a_clear_error(api_ctx):
    _, f, _ = api_ctx
    with pytest.raises(ValueError) as err:
        f["get_obj_pos"]("movable small red block with obj_id 33")
    msg = str(err.value)
    assert "unknown object" in msg and "movable small red block with obj_id 3" in msg
    assert f["get_obj_pos"](3) == f["get_obj_pos"]("movable small red block with obj_id 3")


# ------------------------------------------------------------------------------------ poses
def test_get_obj_pos_single_and_list(api_ctx):
    _, f, ctx = api_ctx
    red, big = name_of(ctx, 3), name_of(ctx, 4)
    p = f["get_obj_pos"](red)
    assert isinstance(p, list) and len(p) == 3 and all(isinstance(v, float) for v in p)
    assert np.allclose(p, ctx.world.pose(3).pos)
    assert p[2] == pytest.approx(0.02, abs=2e-3)
    both = f["get_obj_pos"]([red, big])
    assert isinstance(both, list) and len(both) == 2
    assert np.allclose(both[1], ctx.world.pose(4).pos)
    arr = f["get_obj_positions_np"]([red, big])
    assert isinstance(arr, np.ndarray) and arr.shape == (2, 3) and np.allclose(arr[0], p)


def test_rotation_is_xyzw(api_ctx):
    _, f, ctx = api_ctx
    q = f["get_obj_rot"](name_of(ctx, 3))
    assert np.allclose(np.abs(q), [0, 0, abs(math.sin(YAW / 2)), abs(math.cos(YAW / 2))], atol=2e-3)
    w, x, y, z = ctx.world.pose(3).quat
    assert np.allclose(q, [x, y, z, w])
    assert f["get_obj_rotations_np"]([name_of(ctx, 3)]).shape == (1, 4)
    pos, euler = f["get_obj_pos_dict"]()[name_of(ctx, 3)]
    assert np.allclose(pos, ctx.world.pose(3).pos)
    assert euler[2] == pytest.approx(YAW, abs=2e-3) and abs(euler[0]) < 1e-2 and abs(euler[1]) < 1e-2


def test_bbox_corners_of_a_rotated_block(api_ctx):
    _, f, ctx = api_ctx
    xmin, ymin, zmin, xmax, ymax, zmax = f["get_bbox"](name_of(ctx, 3))
    c = np.asarray(ctx.world.pose(3).pos)
    half = 0.02 * (abs(math.cos(YAW)) + abs(math.sin(YAW)))  # xy half extent of a 0.04 cube at YAW
    assert (xmin, xmax) == pytest.approx((c[0] - half, c[0] + half), abs=1e-3)
    assert (ymin, ymax) == pytest.approx((c[1] - half, c[1] + half), abs=1e-3)
    assert (zmin, zmax) == pytest.approx((0.0, 0.04), abs=2e-3)
    zone = f["get_bbox"](name_of(ctx, 1))
    assert zone[3] - zone[0] == pytest.approx(0.12 * (math.cos(0.3) + math.sin(0.3)), abs=1e-3)  # no x50 hack


def test_denormalize_corners_and_sides(api_ctx):
    _, f, _ = api_ctx
    assert f["denormalize"]([0, 0]) == pytest.approx([0.75, -0.5])   # bottom left of the image
    assert f["denormalize"]([1, 1]) == pytest.approx([0.25, 0.5])    # top right
    assert f["denormalize"]([0.5, 0.5, 0.1]) == pytest.approx([0.5, 0.0, 0.1])
    assert f["denormalize"]([[0, 1], [1, 0]]) == [pytest.approx([0.25, -0.5]), pytest.approx([0.75, 0.5])]
    assert f["get_corner_name"]([0.27, -0.45]) == "top left corner"
    assert f["get_corner_name"]([0.7, 0.45, 0.02]) == "bottom right corner"
    assert f["get_side_name"]([0.5, 0.45]) == "right side"
    assert f["get_side_name"]([0.3, 0.0]) == "top side"
    assert f["get_color"]("fixed blue bowl with obj_id 2") == "blue"


# ------------------------------------------------------------------------------------ occupancy
def test_is_target_occupied_positions_and_names(api_ctx):
    _, f, ctx = api_ctx
    red = name_of(ctx, 3)
    p = f["get_obj_pos"](red)
    assert f["is_target_occupied"](p) == [red]
    assert f["is_target_occupied"]([p[0] + 0.05, p[1]]) == []               # 0.0225 m from its rotated edge
    assert f["is_target_occupied"]([p[0] + 0.05, p[1]], r=0.03) == [red]
    assert f["is_target_occupied"]([0.6, -0.19]) == [name_of(ctx, 2)]      # inside the bowl's disc
    zone = name_of(ctx, 1)
    assert f["is_target_occupied"](zone) == []
    f["put_first_on_second"](red, zone)
    assert f["is_target_occupied"](zone) == [red]
    assert zone in f["is_target_occupied"](red)                              # the zone under it


# ------------------------------------------------------------------------------------ free positions
def footprints(ctx) -> list:
    out = []
    for o in ctx.world.objects:
        pose = ctx.world.pose(o.obj_id)
        if o.kind == "bowl":
            out.append(Point(pose.pos[:2]).buffer(0.06, 64))
            continue
        hx, hy, _ = o.half_extents
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        out.append(Polygon([(pose.pos[0] + c * a - s * b, pose.pos[1] + s * a + c * b)
                            for a, b in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))]))
    return out


def test_random_free_pos_is_free_inside_the_area_and_deterministic(api_ctx):
    _, f, ctx = api_ctx
    shapes = footprints(ctx)
    area = (0.25, 0.0, 0.5, 0.5)  # (xmin, ymin, xmax, ymax): the top right quadrant
    seen = []
    for _ in range(50):
        x, y, z = f["get_random_free_pos"](area=area)
        seen.append((x, y))
        assert z == 0.0
        assert area[0] + FREE_CLEARANCE - 1e-9 <= x <= area[2] - FREE_CLEARANCE + 1e-9
        assert area[1] + FREE_CLEARANCE - 1e-9 <= y <= area[3] - FREE_CLEARANCE + 1e-9
        assert min(s.distance(Point(x, y)) for s in shapes) >= FREE_CLEARANCE - 1e-6
    assert len(set(seen)) > 10  # random, not a fixed point
    # the same episode seed gives the same sequence
    again = PlannerAPI(make_ctx(table_scene())).functions()
    assert [tuple(again["get_random_free_pos"](area=area)[:2]) for _ in range(50)] == seen
    # whole workspace, small clearance, away from a reserved target position
    for _ in range(50):
        x, y, _ = f["get_random_free_pos"](targ=[0.55, 0.35], r=0.02)
        assert math.hypot(x - 0.55, y - 0.35) >= 0.04 - 1e-9
        assert min(s.distance(Point(x, y)) for s in shapes) >= 0.02 - 1e-6
        assert 0.25 <= x <= 0.75 and -0.5 <= y <= 0.5 and math.hypot(x, y) <= 0.84


def test_random_free_pos_full_area_raises(api_ctx):
    _, f, ctx = api_ctx
    zone = f["get_bbox"](name_of(ctx, 1))
    with pytest.raises(ValueError, match="no free position"):
        f["get_random_free_pos"](area=(zone[0], zone[1], zone[3], zone[4]), r=0.1)


# ------------------------------------------------------------------------------------ acting
def test_put_on_block_zone_bowl_and_position(api_ctx):
    _, f, ctx = api_ctx
    red, yellow, purple = name_of(ctx, 3), name_of(ctx, 4), name_of(ctx, 5)
    zone, bowl = name_of(ctx, 1), name_of(ctx, 2)
    # onto a zone: at its centre, resting on the table
    f["put_first_on_second"](yellow, zone)
    # onto a block: on its real top (a small block on a big one)
    f["put_first_on_second"](red, yellow)
    state = ctx.world.state()
    assert P.in_zone(state, 4, 1) and P.resting_on_table(state, 4)
    assert P.resting_on(state, 3, 4) and P.is_stack(state, [4, 3])[0]
    assert np.allclose(state.pos(4)[:2], state.pos(1)[:2], atol=0.01)
    # a block with something on it cannot be picked
    with pytest.raises(ValueError, match="on top of it"):
        f["put_first_on_second"](yellow, [0.4, -0.3])
    # into a bowl: on its floor, below the rim
    f["put_first_on_second"](red, bowl)
    assert P.in_bowl(ctx.world.state(), 3, 2)
    # to an xy position, turned to a quaternion's yaw
    yaw = 0.3
    f["put_first_on_second"](purple, ([0.5, -0.3, 0.0], [0, 0, math.sin(yaw / 2), math.cos(yaw / 2)]))
    pose = ctx.world.pose(5)
    assert np.allclose(pose.pos, [0.5, -0.3, 0.02], atol=0.01)
    assert (pose.yaw - yaw + math.pi / 4) % (math.pi / 2) - math.pi / 4 == pytest.approx(0.0, abs=math.radians(5))
    # stack_objects_in_order: bottom first, on the target
    f["stack_objects_in_order"]([red, purple], [0.45, -0.1])
    state = ctx.world.state()
    assert P.is_stack(state, [3, 5])[0] and np.allclose(state.pos(3)[:2], [0.45, -0.1], atol=0.01)
    assert ctx.attempt_primitives == 6


def test_fixed_objects_and_bad_targets_error_clearly(api_ctx):
    _, f, ctx = api_ctx
    with pytest.raises(ValueError, match="is fixed and cannot be picked"):
        f["put_first_on_second"](name_of(ctx, 2), name_of(ctx, 1))
    with pytest.raises(ValueError, match="unknown object"):
        f["put_first_on_second"]("movable small orange block", name_of(ctx, 1))
    with pytest.raises(ValueError, match="on itself"):
        f["put_first_on_second"](name_of(ctx, 3), name_of(ctx, 3))
    with pytest.raises(ValueError, match="target must be"):
        f["put_first_on_second"](name_of(ctx, 3), [1, 2, 3, 4, 5])
    assert ctx.attempt_primitives == 0


def test_say_and_call_log(api_ctx):
    api, f, _ = api_ctx
    f["say"]("hello")
    f["get_obj_names"]()
    with pytest.raises(ValueError):
        f["get_color"]("nothing")
    assert api.messages == ["hello"]
    assert [e["fn"] for e in api.call_log] == ["say", "get_obj_names", "get_color"]
    assert "error" in api.call_log[-1] and "result" in api.call_log[1]
    assert "get_color('nothing') !! ValueError" in api.log_text()


# ------------------------------------------------------------------------------------ isolation
FORBIDDEN = (mujoco.MjModel, mujoco.MjData, World, EpisodeContext, PlannerAPI)


def reachable_public(root, depth: int = 4):
    """Every object reachable from ``root`` through public attributes / items, ``depth`` deep."""
    seen, frontier, out = set(), [root], []
    for _ in range(depth):
        nxt = []
        for obj in frontier:
            if id(obj) in seen or isinstance(obj, (str, bytes, int, float, bool, type(None))):
                continue
            seen.add(id(obj))
            out.append(obj)
            if isinstance(obj, dict):
                nxt += list(obj.keys()) + list(obj.values())
            elif isinstance(obj, (list, tuple, set)):
                nxt += list(obj)
            if isinstance(obj, np.ndarray):
                continue  # numpy's own attributes lead only to numpy
            for name in dir(obj):
                if name.startswith("_"):
                    continue
                try:
                    nxt.append(getattr(obj, name))
                except Exception:  # noqa: BLE001 - some descriptors refuse
                    pass
        frontier = nxt
    return out


def test_no_public_path_to_the_simulator(api_ctx):
    _, f, ctx = api_ctx
    red = name_of(ctx, 3)
    results = [f["get_obj_names"](), f["get_obj_pos"](red), f["get_obj_rot"](red), f["get_bbox"](red),
               f["get_obj_pos_dict"](), f["get_obj_positions_np"]([red]), f["is_target_occupied"](red),
               f["get_random_free_pos"](), f["denormalize"]([0.5, 0.5]), f["get_color"](red)]
    for root in [f, *f.values(), *results]:
        for obj in reachable_public(root):
            assert not isinstance(obj, FORBIDDEN), f"{type(obj).__name__} reachable from {root!r}"
    # and the sandbox refuses the private routes (closures, globals)
    for code in ("x = get_obj_pos.__closure__", "x = get_obj_pos.__globals__", "x = say._api"):
        with pytest.raises(PlanError, match="SandboxViolation"):
            run_code(code, f)


def test_plan_code_uses_the_api_in_the_sandbox(api_ctx):
    _, f, ctx = api_ctx
    env = dict(f, objects=f["get_obj_names"]())
    code = (
        "blocks = [n for n in objects if ' block ' in n]\n"
        "zone = [n for n in objects if ' zone ' in n][0]\n"
        "for b in blocks:\n"
        "    put_first_on_second(b, zone)\n"
    )
    run_code(code, env)
    state = ctx.world.state()
    order = P.find_stack_order(state, [3, 4, 5])
    assert P.is_stack(state, order)[0] and all(P.in_zone(state, i, 1) for i in order)
    with pytest.raises(PlanError, match="line 1: ValueError: 'fixed blue bowl with obj_id 2' is fixed"):
        run_code("put_first_on_second('fixed blue bowl with obj_id 2', [0.5, 0.0])", env)


def test_capravens_names_run_as_written(api_ctx):
    """CapRavens' prompts call denormalize_xy, denormalize_bbox and stack_objects_in_order(object_names=...)."""
    _, f, ctx = api_ctx
    assert f["denormalize_xy"]([0.9, 0.9]).tolist() == pytest.approx(f["denormalize"]([0.9, 0.9]))
    assert f["denormalize_xy"]([0.0, 1.0]).tolist() == pytest.approx([0.25, -0.5])  # top left
    assert f["denormalize_xy"]([0.5, 1.0], size=(0.12, 0.2)).tolist() == pytest.approx([0.06, 0.0])
    area = f["denormalize_bbox"]([0.5, 0.5, 1.0, 1.0])  # the top right quadrant of the image
    assert area == pytest.approx([0.25, 0.0, 0.5, 0.5])
    x, y, _ = f["get_random_free_pos"](area=area)
    assert 0.25 <= x <= 0.5 and 0.0 <= y <= 0.5
    red, purple = name_of(ctx, 3), name_of(ctx, 5)
    f["stack_objects_in_order"](object_names=[red, purple], targ=[0.45, -0.1])
    assert P.is_stack(ctx.world.state(), [3, 5])[0]
    with pytest.raises(ValueError, match="denormalize_bbox expects"):
        f["denormalize_bbox"]([0.0, 1.0])
