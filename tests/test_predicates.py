"""Unit tests of the shared geometric predicates on hand-built states (no physics)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from capmj.sim.objects import BOWL_HEIGHT, ObjectSpec
from capmj.sim.state import Pose, SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Target


def yaw_quat(yaw: float) -> tuple[float, float, float, float]:
    return (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))


def tilt_quat(angle: float) -> tuple[float, float, float, float]:
    """Rotation about world x by ``angle`` (w, x, y, z)."""
    return (math.cos(angle / 2), math.sin(angle / 2), 0.0, 0.0)


def block(i: int, pos, size: str = "small", color: str = "red") -> ObjectSpec:
    return ObjectSpec(i, "block", color, tuple(pos), size=size)


def state_of(objs, poses: dict | None = None) -> SceneState:
    s = SceneState.from_specs(objs)
    if poses:
        p = dict(s.poses)
        for k, v in poses.items():
            p[k] = v if isinstance(v, Pose) else Pose(tuple(v))
        s = SceneState(s.objects, p)
    return s


# --------------------------------------------------------------------------------------- areas
def test_area_bounds_and_names():
    assert P.area_bounds("top left") == (0.25, 0.5, -0.5, 0.0)
    assert P.area_bounds("left-top area") == (0.25, 0.5, -0.5, 0.0)
    assert P.area_bounds("bottom") == (0.5, 0.75, -0.5, 0.5)
    assert P.area_bounds("right") == (0.25, 0.75, 0.0, 0.5)
    for bad in ("middle", "", "top bottom", "left left"):
        with pytest.raises(ValueError):
            P.area_bounds(bad)


@pytest.mark.parametrize(
    "pos,area,expected",
    [
        ((0.3, -0.2), "top left", True),
        ((0.3, -0.2), "top right", False),
        ((0.6, -0.2), "bottom left", True),
        ((0.6, 0.2), "bottom right", True),
        ((0.6, 0.2), "top", False),
        ((0.4, 0.0), "left", False),  # on the split line: neither half
        ((0.4, 0.0), "right", False),
        ((0.5, 0.1), "top", False),
        ((0.25, -0.5), "top left", True),  # workspace corner is inclusive
        ((0.8, 0.1), "bottom right", False),  # off the workspace
        ((0.6, 0.1), (0.5, 0.7, 0.0, 0.2), True),
    ],
)
def test_in_area(pos, area, expected):
    assert P.in_area(pos, area) is expected


# --------------------------------------------------------------------------------------- zones
def _zone_state(yaw=0.0, scale=1.0, block_xy=(0.5, 0.0)):
    zone = ObjectSpec(1, "zone", "green", (0.5, 0.0, 0.0005), yaw=yaw, scale=scale)
    b = block(2, (block_xy[0], block_xy[1], 0.02))
    return state_of([zone, b])


def test_in_zone_edges_yaw_and_scale():
    assert P.in_zone(_zone_state(block_xy=(0.559, 0.0)), 2, 1)
    assert not P.in_zone(_zone_state(block_xy=(0.561, 0.0)), 2, 1)
    assert P.in_zone(_zone_state(block_xy=(0.5, -0.059)), 2, 1)
    # along the diagonal: a 45°-rotated zone reaches 0.0849 m along x, an aligned one 0.06 m
    assert not P.in_zone(_zone_state(yaw=0.0, block_xy=(0.575, 0.0)), 2, 1)
    assert P.in_zone(_zone_state(yaw=math.pi / 4, block_xy=(0.575, 0.0)), 2, 1)
    assert not P.in_zone(_zone_state(yaw=math.pi / 4, block_xy=(0.55, 0.05)), 2, 1)
    assert P.in_zone(_zone_state(scale=2.0, block_xy=(0.61, 0.1)), 2, 1)
    assert not P.in_zone(_zone_state(scale=2.0, block_xy=(0.63, 0.0)), 2, 1)
    s = _zone_state(block_xy=(0.58, 0.0))
    assert P.zone_outside_distance(s, 2, 1) == pytest.approx(0.02)
    assert P.zone_outside_distance(_zone_state(), 2, 1) == 0.0


def test_objects_in_zone_filters_kinds():
    zone = ObjectSpec(1, "zone", "green", (0.5, 0.0, 0.0005))
    objs = [zone, block(2, (0.5, 0.0, 0.02)), block(3, (0.7, 0.3, 0.02)),
            ObjectSpec(4, "ball", "red", (0.52, 0.02, 0.03))]
    s = state_of(objs)
    assert P.objects_in_zone(s, 1) == [2]
    assert P.objects_in_zone(s, 1, kinds=("block", "ball")) == [2, 4]


# --------------------------------------------------------------------------------------- bowls
def test_in_bowl():
    bowl = ObjectSpec(1, "bowl", "red", (0.5, 0.1, BOWL_HEIGHT / 2))
    floor = P.bowl_floor_z(bowl.pos)
    assert floor == pytest.approx(0.004)
    z = floor + 0.02
    assert P.in_bowl(state_of([bowl, block(2, (0.5 + 0.049, 0.1, z))]), 2, 1)
    assert not P.in_bowl(state_of([bowl, block(2, (0.5 + 0.051, 0.1, z))]), 2, 1)
    assert P.in_bowl(state_of([bowl, block(2, (0.5, 0.1 - 0.03, z))]), 2, 1)
    # above the rim (e.g. held over the bowl or resting on its wall)
    assert not P.in_bowl(state_of([bowl, block(2, (0.5, 0.1, BOWL_HEIGHT + 0.001))]), 2, 1)


# --------------------------------------------------------------------------------------- stacks
def _tower(sizes=("small", "small", "small"), x=0.5, y=0.0, offsets=None, dz=None):
    objs, z, prev_h = [], 0.0, None
    for k, s in enumerate(sizes):
        b = block(k + 1, (0, 0, 0), size=s)
        h = b.height
        z = h / 2 if prev_h is None else z + (prev_h + h) / 2 + (dz[k] if dz else 0.0)
        ox, oy = offsets[k] if offsets else (0.0, 0.0)
        objs.append(b.moved((x + ox, y + oy, z)))
        prev_h = h
    return state_of(objs)


def test_is_stack_accepts_a_good_tower():
    s = _tower()
    assert P.is_stack(s, [1, 2, 3]) == (True, "3 object(s) stacked")
    assert P.is_stack(s, [1])[0]
    mixed = _tower(("big", "small", "small"))
    assert P.is_stack(mixed, [1, 2, 3])[0]


def test_is_stack_order_matters():
    s = _tower()
    ok, why = P.is_stack(s, [2, 1, 3])
    assert not ok and "not on the table" in why
    assert P.find_stack_order(s, [3, 1, 2]) == [1, 2, 3]


@pytest.mark.parametrize(
    "kw,word",
    [
        ({"offsets": [(0, 0), (0.0, 0.015), (0.021, 0.0)]}, "off the stack axis"),
        ({"offsets": [(0, 0), (0.015, 0.0), (0.015, 0.014)]}, "off the stack axis"),
        ({"dz": [0, 0.016, 0]}, "not resting on"),
        ({"dz": [0, 0, -0.016]}, "not resting on"),
    ],
)
def test_is_stack_tolerances(kw, word):
    ok, why = P.is_stack(_tower(**kw), [1, 2, 3])
    assert not ok and word in why


def test_is_stack_within_tolerances():
    s = _tower(offsets=[(0, 0), (0.014, 0.0), (0.0, 0.019)], dz=[0, 0.014, -0.014])
    assert P.is_stack(s, [1, 2, 3])[0]


def test_is_stack_rejects_tilt_and_floating_bottom():
    s = _tower()
    p = dict(s.poses)
    p[3] = Pose(p[3].pos, tilt_quat(math.radians(30)))
    assert P.toppled(SceneState(s.objects, p), 3)
    ok, why = P.is_stack(SceneState(s.objects, p), [1, 2, 3])
    assert not ok and "tilted" in why
    p[3] = Pose(p[3].pos, tilt_quat(math.radians(10)))
    assert not P.toppled(SceneState(s.objects, p), 3)
    assert P.is_stack(SceneState(s.objects, p), [1, 2, 3])[0]
    # a cube lying on another face (90°) is upright again
    p[3] = Pose(p[3].pos, tilt_quat(math.radians(90)))
    assert P.is_stack(SceneState(s.objects, p), [1, 2, 3])[0]
    lifted = _tower(dz=None)
    q = {i: Pose((pp.pos[0], pp.pos[1], pp.pos[2] + 0.02)) for i, pp in lifted.poses.items()}
    ok, why = P.is_stack(SceneState(lifted.objects, q), [1, 2, 3])
    assert not ok and "not on the table" in why
    assert not P.is_stack(s, [])[0]


def test_build_tower_finds_tallest_partial_stack():
    s = _tower(("small",) * 4)
    assert P.build_tower(s, [1, 2, 3, 4]) == [1, 2, 3, 4]
    p = dict(s.poses)
    p[3] = Pose((0.6, 0.2, 0.02))  # pulled out: 4 floats
    s2 = SceneState(s.objects, p)
    assert P.build_tower(s2, [1, 2, 3, 4]) == [1, 2]
    zone = ObjectSpec(9, "zone", "green", (0.5, 0.0, 0.0005))
    s3 = SceneState(s.objects + (zone,), {**s.poses, 9: Pose(zone.pos)})
    assert P.build_tower(s3, [1, 2, 3, 4], zone_id=9) == [1, 2, 3, 4]
    far = SceneState(s.objects + (zone.moved((0.7, 0.3, 0.0005)),), {**s.poses, 9: Pose((0.7, 0.3, 0.0005))})
    assert P.build_tower(far, [1, 2, 3, 4], zone_id=9) == []
    assert P.build_tower(s, [1, 2, 3, 4], accept=lambda lvl, i: i != 3) == [1, 2]


# --------------------------------------------------------------------------------------- motion
def test_moved_less_than():
    s = state_of([block(1, (0.5, 0.0, 0.02))])
    assert P.moved_less_than(s, 1, (0.5, 0.029, 0.02))
    assert not P.moved_less_than(s, 1, (0.5, 0.031, 0.02))
    assert not P.moved_less_than(s, 1, (0.5, 0.02, 0.045))  # 3-D distance


# --------------------------------------------------------------------------------------- shapes
def test_fit_circle():
    ang = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    pts = np.column_stack([0.5 + 0.1 * np.cos(ang), 0.1 + 0.1 * np.sin(ang), np.full(8, 0.02)])
    c, r, res = P.fit_circle(pts)
    assert np.allclose(c, [0.5, 0.1], atol=1e-9) and r == pytest.approx(0.1) and res < 1e-9
    pts[0, 0] += 0.012
    _, _, res = P.fit_circle(pts)
    assert res > 0.005
    _, r, res = P.fit_circle([(0.4, 0.0), (0.5, 0.1), (0.6, 0.2)])
    assert math.isinf(r) and math.isinf(res)
    assert math.isinf(P.fit_circle([(0.4, 0.0), (0.5, 0.1)])[1])


def _grid(rows, cols, pitch, yaw=0.0, origin=(0.5, 0.0)):
    cs, sn = math.cos(yaw), math.sin(yaw)
    pts = []
    for i in range(rows):
        for j in range(cols):
            u, v = j * pitch, i * pitch
            pts.append((origin[0] + cs * u - sn * v, origin[1] + sn * u + cs * v))
    return np.array(pts)


@pytest.mark.parametrize("rows,cols", [(3, 3), (2, 2), (2, 3), (1, 4)])
@pytest.mark.parametrize("yaw", [0.0, 0.3, math.pi / 4, 1.2])
def test_is_grid_accepts_rotated_grids(rows, cols, yaw):
    pts = _grid(rows, cols, 0.05, yaw)
    rng = np.random.default_rng(0)
    ok, why = P.is_grid(pts[rng.permutation(len(pts))], rows, cols, (0.04, 0.06), 0.015)
    assert ok, why


def test_is_grid_rejections():
    pts = _grid(3, 3, 0.05, 0.3)
    assert not P.is_grid(pts, 2, 4)[0]  # wrong count
    assert not P.is_grid(_grid(3, 3, 0.07), 3, 3, (0.04, 0.06))[0]  # pitch too big
    bad = pts.copy()
    bad[4] += (0.02, 0.0)
    assert not P.is_grid(bad, 3, 3, (0.04, 0.06), 0.015)[0]  # one point out of line
    ok = pts.copy()
    ok[4] += (0.005, 0.0)
    assert P.is_grid(ok, 3, 3, (0.04, 0.06), 0.015)[0]


# --------------------------------------------------------------------------------------- reward
def test_ravens_reward_one_to_one_and_replace():
    objs = [block(1, (0.5, 0.0, 0.02)), block(2, (0.5, 0.0, 0.06))]
    s = state_of(objs, {2: (0.5, 0.0, 0.02)})  # both on the first slot
    t = (Target((0.5, 0.0, 0.02)), Target((0.6, 0.0, 0.02)))
    g = OracleGoal((1, 2), t, ((1, 1), (1, 1)))
    assert P.ravens_reward([g], s) == pytest.approx(0.5)
    g_rep = OracleGoal((1, 2), t, ((1, 1), (1, 1)), replace=True)
    assert P.ravens_reward([g_rep], s) == pytest.approx(1.0)
    s_ok = state_of(objs, {2: (0.6, 0.009, 0.02)})
    assert P.ravens_reward([g], s_ok) == pytest.approx(1.0)
    s_far = state_of(objs, {2: (0.6, 0.011, 0.02)})
    assert P.ravens_reward([g], s_far) == pytest.approx(0.5)
    s_high = state_of(objs, {2: (0.6, 0.0, 0.036)})
    assert P.ravens_reward([g], s_high) == pytest.approx(0.5)
    # matching needs augmenting: object 1 could take either slot, object 2 only slot 0
    s_aug = state_of(objs, {1: (0.5, 0.0, 0.02), 2: (0.5, 0.0, 0.02)})
    g2 = OracleGoal((1, 2), (Target((0.5, 0.0, 0.02)),) * 2, ((1, 1), (1, 0)))
    assert P.ravens_reward([g2], s_aug) == pytest.approx(1.0)
    assert P.ravens_reward([], s) == 0.0


def test_ravens_reward_zone_metric_and_rotation():
    objs = [block(1, (0.55, 0.05, 0.02))]
    s = state_of(objs)
    g = OracleGoal((1,), (Target((0.5, 0.0, 0.0)),), ((1,),), metric="zone", zone_size=0.12)
    assert P.ravens_reward([g], s) == 1.0
    g_small = OracleGoal((1,), (Target((0.5, 0.0, 0.0)),), ((1,),), metric="zone", zone_size=0.08)
    assert P.ravens_reward([g_small], s) == 0.0
    rot = OracleGoal((1,), (Target((0.55, 0.05, 0.02), yaw=0.0),), ((1,),), rotations=True)
    assert P.ravens_reward([rot], s) == 1.0
    s_rot = state_of(objs, {1: Pose((0.55, 0.05, 0.02), yaw_quat(math.radians(30)))})
    assert P.ravens_reward([rot], s_rot) == 0.0
    s_sym = state_of(objs, {1: Pose((0.55, 0.05, 0.02), yaw_quat(math.radians(95)))})
    assert P.ravens_reward([rot], s_sym) == 1.0  # cube: 90° symmetry


def test_short_label():
    assert P.short_label(block(3, (0.5, 0, 0.03), size="big", color="red")) == "big red block 3"
    assert P.short_label(ObjectSpec(1, "zone", "green", (0.5, 0, 0))) == "green zone 1"


# ================================================================== generated tasks 6–10 predicates
def zone(i: int, pos, yaw: float = 0.0, color: str = "green") -> ObjectSpec:
    return ObjectSpec(i, "zone", color, tuple(pos), yaw)


def test_largest_odd_and_group_sizes():
    assert [P.largest_odd_at_most(n) for n in range(0, 7)] == [0, 1, 1, 3, 3, 5, 5]
    assert P.group_sizes(7, 3) == [3, 3, 1] and P.group_sizes(8, 2) == [2, 2, 2, 2] and P.group_sizes(8, 3) == [3, 3, 2]


def test_zone_color_counts_and_zone_stacks():
    objs = [zone(1, (0.5, 0.0, 0.0005)), zone(2, (0.5, 0.3, 0.0005), color="blue"),
            block(3, (0.5, 0.0, 0.02)), block(4, (0.5, 0.0, 0.06), color="blue"), block(5, (0.5, 0.3, 0.02)),
            block(6, (0.3, -0.3, 0.02))]
    s = state_of(objs)
    assert P.zone_color_counts(s, 1) == {"red": [3], "blue": [4]}
    a, b = P.zone_stacks(s, [1, 2], [3, 4, 5, 6])
    assert a.ok and a.tower == (3, 4) and a.members == (3, 4)
    assert b.ok and b.members == (5,)
    # the upper block slid off the axis: two members, a tower of one
    s2 = state_of(objs, {4: (0.525, 0.0, 0.06)})
    a = P.zone_stacks(s2, [1], [3, 4])[0]
    assert not a.ok and a.tower == (3,) and "off the stack axis" in a.why
    # two blocks side by side on the table in one zone: both stacks of one, not one stack
    s3 = state_of(objs, {4: (0.5, 0.045, 0.02)})
    a = P.zone_stacks(s3, [1], [3, 4])[0]
    assert not a.ok and len(a.tower) == 1 and "off the stack axis" in a.why
    assert P.zone_stacks(s, [2], [3, 4])[0].why == "empty"


def test_row_on_line_spacing_offsets_and_midpoint():
    e = np.array([math.cos(0.4), math.sin(0.4)])
    n = np.array([-e[1], e[0]])
    mid = np.array([0.5, 0.05])
    pts = [mid + (k - 2) * 0.08 * e for k in range(5)]
    rep = P.row_on_line(pts[::-1], mid, e, 0.08)
    assert rep.ok and rep.order == (4, 3, 2, 1, 0) and max(rep.offsets) < 1e-12 and rep.midpoint_error < 1e-12
    # within tolerance: 0.012 off the line, a gap 0.012 longer
    ok = [p + 0.012 * n for p in pts]
    ok[-1] = ok[-1] + 0.012 * e
    assert P.row_on_line(ok, mid, e, 0.08).ok
    bad = list(pts)
    bad[-1] = bad[-1] + 0.02 * e  # uneven gap
    rep = P.row_on_line(bad, mid, e, 0.08)
    assert not rep.ok and any("apart" in r for r in rep.reasons)
    bad = list(pts)
    bad[1] = bad[1] + 0.02 * n  # off the line
    assert any("off the line" in r for r in P.row_on_line(bad, mid, e, 0.08).reasons)
    slid = [p + 0.03 * e for p in pts]  # even and on the line, but not centred
    rep = P.row_on_line(slid, mid, e, 0.08)
    assert not rep.ok and rep.reasons == (rep.reasons[0],) and "midpoint" in rep.reasons[0]
    assert not P.row_on_line([], mid, e, 0.08).ok


def test_fixture_slots_and_occupants():
    fx = ObjectSpec(1, "fixture", "gray", (0.5, 0.0, 0.02), math.pi / 6)
    slots = P.fixture_slots(fx.pos, fx.yaw)
    c, s_ = math.cos(math.pi / 6), math.sin(math.pi / 6)
    assert np.allclose(slots[1], (0.5 + 0.04 * c, 0.04 * s_, 0.02)) and np.allclose(slots[2], (0.5 - 0.04 * s_, 0.04 * c, 0.02))
    blocks = [block(2 + k, tuple(p), color=col) for k, (p, col) in enumerate(zip(slots, ("red", "blue", "green")))]
    st = state_of([fx, *blocks])
    assert P.slot_occupants(st, 1, [2, 3, 4]) == [2, 3, 4]
    # 1.5 cm out of the slot: empty; 1 cm: still in; tilted: not in
    xdir = np.array([c, s_, 0.0])
    assert P.slot_occupants(state_of([fx, *blocks], {3: tuple(slots[1] + 0.015 * xdir)}), 1, [2, 3, 4]) == [2, None, 4]
    assert P.slot_occupants(state_of([fx, *blocks], {3: tuple(slots[1] + 0.01 * xdir)}), 1, [2, 3, 4]) == [2, 3, 4]
    tilted = state_of([fx, *blocks], {4: Pose(tuple(slots[2]), tilt_quat(math.radians(30)))})
    assert P.slot_occupants(tilted, 1, [2, 3, 4]) == [2, 3, None]
    # the farthest point of the L (outer end of the long wall) is FIXTURE_RADIUS from the origin
    assert P.FIXTURE_RADIUS == pytest.approx(math.hypot(0.07, 0.03)) and P.FIXTURE_RADIUS > fx.footprint_radius


# --------------------------------------------------------------------------------------- generated tasks 1–5
def _blocks_at(points, colors=None, yaws=None):
    """Small blocks at the given (x, y[, z]) centres (z defaults to the table), optional yaws."""
    objs, poses = [], {}
    for k, p in enumerate(points):
        pos = (float(p[0]), float(p[1]), float(p[2]) if len(p) > 2 else 0.02)
        objs.append(block(k + 1, pos, color=(colors[k] if colors else "red")))
        poses[k + 1] = Pose(pos, yaw_quat(yaws[k] if yaws is not None else 0.0))
    return objs, poses


def _ring(n, r, centre=(0.5, 0.0), z=0.02, phase=0.0):
    ang = phase + 2 * np.pi * np.arange(n) / n
    return [(centre[0] + r * math.cos(a), centre[1] + r * math.sin(a), z) for a in ang], list(ang)


def test_footprint_touching_and_supporters():
    objs, poses = _blocks_at([(0.5, 0.0), (0.545, 0.0), (0.5, 0.0405), (0.5225, 0.02, 0.06)])
    s = state_of(objs, poses)
    assert P.footprint(s, 1).area == pytest.approx(0.0016)
    pairs = {(a, b) for a, b, _ in P.touching_pairs(s, [1, 2, 3])}
    assert pairs == {(1, 3)}  # 0.5 mm apart; 1 and 2 have 5 mm between them
    assert sorted(P.supporters(s, 4, [1, 2, 3])) == [1, 2, 3]
    turned = dict(poses)
    turned[2] = Pose((0.545, 0.0, 0.02), yaw_quat(math.pi / 4))  # a corner now reaches within 1 mm
    assert (1, 2) in {(a, b) for a, b, _ in P.touching_pairs(state_of(objs, turned), [1, 2])}
    high = dict(poses)
    high[4] = Pose((0.5225, 0.02, 0.08))  # floating 2 cm above: rests on nothing
    assert P.supporters(state_of(objs, high), 4, [1, 2, 3]) == []


def test_in_zone_is_the_centre_rule_honouring_scale_and_yaw():
    zone = ObjectSpec(9, "zone", "blue", (0.5, 0.0, 0.0005), yaw=0.3, scale=2.0)
    objs, poses = _blocks_at([(0.5, 0.0), (0.5, 0.11), (0.5, 0.2)])
    s = state_of([zone] + objs, poses)
    assert P.in_zone(s, 1, 9)
    assert P.in_zone(s, 2, 9)      # centre in, a corner out: in
    assert not P.in_zone(s, 3, 9)  # centre out


def _layer(side, pitch, z=0.02, yaw=0.0, centre=(0.5, 0.0)):
    cs, sn = math.cos(yaw), math.sin(yaw)
    pts = []
    for i in range(side):
        for j in range(side):
            u, v = (j - (side - 1) / 2) * pitch, (i - (side - 1) / 2) * pitch
            pts.append((centre[0] + cs * u - sn * v, centre[1] + sn * u + cs * v, z))
    return pts


def test_is_layer_grid_height_and_near_miss():
    pts = _layer(3, 0.05, yaw=0.4)
    objs, poses = _blocks_at(pts, yaws=[0.4] * 9)
    ids = list(range(1, 10))
    assert P.is_layer(state_of(objs, poses), ids, 3, 3, 0, (0.04, 0.06))[0]
    off = dict(poses)
    p = pts[4]
    off[5] = Pose((p[0] + 0.02, p[1], p[2]), yaw_quat(0.4))  # one block 2 cm off the grid
    ok, why = P.is_layer(state_of(objs, off), ids, 3, 3, 0, (0.04, 0.06))
    assert not ok and "misaligned" in why
    ok, why = P.is_layer(state_of(objs, poses), ids, 3, 3, 1, (0.04, 0.06))  # wrong level
    assert not ok and "layer 2" in why
    tilted = dict(poses)
    tilted[3] = Pose(pts[2], tilt_quat(math.radians(30)))
    assert "tilted" in P.is_layer(state_of(objs, tilted), ids, 3, 3, 0, (0.04, 0.06))[1]


def test_circle_of_and_alternation():
    pts, ang = _ring(8, 0.09)
    cols = ["red", "blue"] * 4
    objs, poses = _blocks_at(pts, cols, ang)
    s = state_of(objs, poses)
    ids = list(range(1, 9))
    ok, c, r, _ = P.circle_of(s, ids, min_radius=0.04)
    assert ok and np.allclose(c, (0.5, 0.0)) and r == pytest.approx(0.09)
    assert P.alternates(s, ids, c)[0]
    swapped = ["red", "blue", "blue", "red", "red", "blue", "red", "blue"]  # two same-colour neighbours
    objs2, poses2 = _blocks_at(pts, swapped, ang)
    ok, why = P.alternates(state_of(objs2, poses2), ids, c)
    assert not ok and "neighbours of the same colour" in why
    assert not P.circle_of(s, ids, min_radius=0.1)[0]  # too small
    bumped = dict(poses)
    bumped[3] = Pose((pts[2][0], pts[2][1] + 0.03, 0.02))  # 3 cm outwards
    ok, _, _, why = P.circle_of(state_of(objs, bumped), ids)
    assert not ok and "block 3" in why
    three, _ = _blocks_at([(0.4, 0.0), (0.5, 0.0), (0.6, 0.0)], ["red", "blue", "red"])
    assert not P.circle_of(state_of(three), [1, 2, 3])[0]  # collinear
    assert not P.alternates(state_of(three), [1, 2, 3], (0.5, 0.1))[0]  # odd count cannot alternate


def test_concentric_circles():
    inner, a1 = _ring(4, 0.06)
    outer, a2 = _ring(8, 0.12, phase=0.2)
    objs, poses = _blocks_at(inner + outer, ["red"] * 4 + ["blue"] * 8, a1 + a2)
    ids1, ids2 = [1, 2, 3, 4], list(range(5, 13))
    assert P.concentric(state_of(objs, poses), ids1, ids2)[0]
    shifted_pts, _ = _ring(8, 0.12, centre=(0.53, 0.0), phase=0.2)  # outer circle 3 cm off
    objs2, poses2 = _blocks_at(inner + shifted_pts, ["red"] * 4 + ["blue"] * 8, a1 + a2)
    ok, why = P.concentric(state_of(objs2, poses2), ids1, ids2)
    assert not ok and "centres are 0.030 m apart" in why
    close_pts, _ = _ring(8, 0.09, phase=0.2)  # radii only 3 cm apart
    objs3, poses3 = _blocks_at(inner + close_pts, ["red"] * 4 + ["blue"] * 8, a1 + a2)
    assert "differ by less" in P.concentric(state_of(objs3, poses3), ids1, ids2)[1]


# ================================================================== the package's surface
def test_every_concept_module_is_exported_whole_and_documented():
    """``capmj.tasks.predicates`` re-exports exactly what its concept modules define as public, so a
    predicate added to a module but not to the package (or the reverse) fails here."""
    import importlib
    import inspect
    import pkgutil

    names: list[str] = []
    for info in pkgutil.iter_modules(P.__path__):
        module = importlib.import_module(f"{P.__name__}.{info.name}")
        names += module.__all__
        for n in module.__all__:
            assert getattr(P, n) is getattr(module, n), n
    assert len(P.__all__) == len(set(P.__all__))
    assert sorted(names) == sorted(P.__all__)
    for n in P.__all__:
        obj = getattr(P, n)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            assert inspect.getdoc(obj), f"{n} has no docstring (the generator's prompt shows it)"
