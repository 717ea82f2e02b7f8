"""Foundation tests on real MuJoCo physics: determinism, suction, placing, towers, bowls."""

from __future__ import annotations

import numpy as np
import pytest

from capmj.sim.objects import BOWL_HEIGHT, ObjectSpec
from capmj.sim.primitives import Primitives
from capmj.sim.world import World
from capmj.tasks import predicates as P


def small(i: int, color: str, x: float, y: float, z: float = 0.02, yaw: float = 0.0) -> ObjectSpec:
    return ObjectSpec(i, "block", color, (x, y, z), yaw, "small")


def test_same_specs_same_model_and_trajectory() -> None:
    specs = [small(1, "red", 0.5, 0.0, yaw=0.3), small(2, "blue", 0.4, 0.2), ObjectSpec(3, "zone", "green", (0.6, -0.2, 0.0005))]
    a, b = World(specs), World(specs)
    assert a.xml == b.xml
    for w in (a, b):
        Primitives(w).pick_and_place(np.array(w.pose(1).pos), np.array([0.6, -0.2]), 0.7)
    assert a.steps == b.steps
    np.testing.assert_array_equal(a.data.qpos, b.data.qpos)
    # a different scene compiles to a different model
    assert World(specs[:2]).xml != a.xml


def test_snapshot_restore_replays_identically() -> None:
    w = World([small(1, "red", 0.5, 0.0), small(2, "blue", 0.4, 0.2)])
    snap = w.snapshot()
    p = Primitives(w)
    p.pick_and_place(np.array(w.pose(1).pos), np.array([0.55, -0.2]))
    first = w.data.qpos.copy()
    w.restore(snap)
    assert np.allclose(w.pose(1).pos, (0.5, 0.0, 0.02), atol=1e-3)
    p2 = Primitives(w)
    p2.pick_and_place(np.array(w.pose(1).pos), np.array([0.55, -0.2]))
    np.testing.assert_array_equal(w.data.qpos, first)


def test_suction_grips_only_movable_objects_in_contact() -> None:
    w = World([small(1, "red", 0.5, 0.0), ObjectSpec(2, "bowl", "blue", (0.45, 0.25, BOWL_HEIGHT / 2)),
               ObjectSpec(3, "ball", "gold", (0.6, -0.25, 0.03))])
    assert w.suction.grip() is None  # nothing touched at home
    p = Primitives(w)
    for fixed in (2, 3):
        res = p.pick_and_place(np.array(w.pose(fixed).pos), np.array([0.4, -0.1]))
        assert not res.ok and res.status == "no_grip" and res.obj_id is None
        assert w.suction.held is None
    assert np.allclose(w.pose(1).pos, (0.5, 0.0, 0.02), atol=2e-3)  # untouched


def test_suction_holds_through_fast_transit() -> None:
    w = World([small(1, "red", 0.3, -0.35), ObjectSpec(2, "block", "blue", (0.7, 0.35, 0.03), 0.0, "big")])
    offsets: list[float] = []

    def watch(world: World) -> None:
        if world.suction.held == 1:
            offsets.append(float(np.linalg.norm(world.tip_pose()[0] - np.asarray(world.pose(1).pos))))

    w.add_frame_listener(watch, 5)
    res = Primitives(w).pick_and_place(np.array(w.pose(1).pos), np.array([0.7, 0.35, 0.08]))
    assert res.ok and res.obj_id == 1
    assert len(offsets) > 20  # carried for a while across the whole workspace diagonal
    assert max(offsets) - min(offsets) < 0.003  # no slip while carried fast
    assert P.is_stack(w.state(), [2, 1])[0]


def test_held_object_and_cup_do_not_collide_but_both_collide_with_the_rest() -> None:
    """While the weld holds a block, the cup–block contact is filtered out (the weld fixes their
    pose); the block still lands on the table, the filter ends with the release, and restoring a
    snapshot taken mid-carry brings the filter back with the weld."""
    from capmj.sim.suction import CUP

    w = World([small(1, "red", 0.5, 0.0), small(2, "blue", 0.4, -0.2)])
    p = Primitives(w)
    seen: list[set[int]] = []
    snaps = []

    def watch(world: World) -> None:
        if world.suction.held == 1:
            seen.append(world.contacts_of(1))
            if not snaps:
                snaps.append(world.snapshot())

    w.add_frame_listener(watch, 5)
    res = p.pick_and_place(np.array(w.pose(1).pos), np.array([0.55, 0.25]))
    assert res.ok and len(seen) > 20
    assert all(CUP not in owners for owners in seen)
    assert any(0 in owners for owners in seen)  # it touched the table while still held: the place
    affinity = w.model.geom_conaffinity.copy()
    assert affinity[w.cup_geom] != 0  # released: the cup collides as compiled
    w.restore(snaps[0])
    assert w.suction.held == 1 and w.model.geom_conaffinity[w.cup_geom] == 0
    w.suction.release()
    assert np.array_equal(w.model.geom_conaffinity, affinity)


def test_block_placed_on_block_rests_on_it() -> None:
    w = World([small(1, "red", 0.45, 0.1), small(2, "blue", 0.6, -0.15)])
    res = Primitives(w).pick_and_place(np.array(w.pose(1).pos), np.array(w.pose(2).pos[:2]))
    assert res.ok
    state = w.state()
    assert P.resting_on(state, 1, 2)
    assert np.linalg.norm(state.pos(1)[:2] - state.pos(2)[:2]) < 0.005
    assert state.poses[1].tilt < np.radians(3)


def test_tower_of_six_survives_a_pick_and_place_next_to_it() -> None:
    tower = [small(i + 1, c, 0.5, 0.0, 0.02 + 0.04 * i) for i, c in
             enumerate(["red", "blue", "green", "yellow", "orange", "purple"])]
    w = World(tower + [small(7, "pink", 0.5, -0.12), small(8, "cyan", 0.42, 0.09)])
    w.settle()
    ids = [1, 2, 3, 4, 5, 6]
    assert P.is_stack(w.state(), ids)[0]
    p = Primitives(w)
    assert p.pick_and_place(np.array(w.pose(7).pos), np.array([0.5, 0.12])).ok  # across the tower
    assert p.pick_and_place(np.array(w.pose(8).pos), np.array([0.58, -0.08])).ok  # next to it
    ok, why = P.is_stack(w.state(), ids)
    assert ok, why
    assert np.linalg.norm(w.state().pos(6)[:2] - np.array([0.5, 0.0])) < 0.01


def test_block_dropped_in_bowl_stays_in_bowl() -> None:
    w = World([small(1, "red", 0.45, -0.2), ObjectSpec(2, "bowl", "blue", (0.55, 0.15, BOWL_HEIGHT / 2))])
    p = Primitives(w)
    m = p.motion
    pos = np.array(w.pose(1).pos)
    m.move_to(np.array([pos[0], pos[1], 0.2]), m.commanded_yaw())
    m.move_to(np.array([pos[0], pos[1], 0.0]), m.commanded_yaw(), speed=0.2, stop=lambda: w.suction.touching() is not None)
    assert w.suction.grip() == 1
    # carry it 8 cm above the rim and let go off-centre: it must fall in and stay in
    m.move_to(np.array([0.57, 0.16, 0.16]), m.commanded_yaw())
    w.suction.release()
    w.settle(2000)
    state = w.state()
    assert P.in_bowl(state, 1, 2), state.pos(1)
    assert state.pos(1)[2] < BOWL_HEIGHT


def test_unreachable_place_is_a_typed_result() -> None:
    w = World([small(1, "red", 0.5, 0.0)])
    res = Primitives(w).pick_and_place(np.array(w.pose(1).pos), np.array([1.6, 0.0, 0.1]))
    assert not res.ok and res.status == "unreachable"
    assert "out of reach" in res.message
    # the gripped block is put back down, not left hanging from the cup
    assert w.suction.held is None
    assert np.allclose(w.pose(1).pos, (0.5, 0.0, 0.02), atol=0.01)


@pytest.mark.parametrize("yaw", [0.0, 0.6, -1.2])
def test_place_yaw_is_respected(yaw: float) -> None:
    w = World([small(1, "red", 0.4, 0.2, yaw=0.3)])
    res = Primitives(w).pick_and_place(np.array(w.pose(1).pos), np.array([0.6, -0.1]), yaw)
    assert res.ok
    d = (w.pose(1).yaw - yaw + np.pi / 4) % (np.pi / 2) - np.pi / 4
    assert abs(d) < np.radians(3)
    assert np.linalg.norm(np.asarray(w.pose(1).pos[:2]) - np.array([0.6, -0.1])) < 0.005


_PROCESS_SCRIPT = """
import hashlib, numpy as np
from capmj.sim.objects import ObjectSpec
from capmj.sim.primitives import Primitives
from capmj.sim.world import World
w = World([ObjectSpec(1, "block", "red", (0.5, 0.0, 0.02), 0.3, "small"), ObjectSpec(2, "block", "blue", (0.4, 0.2, 0.03), 0.0, "big")])
Primitives(w).pick_and_place(np.array(w.pose(1).pos), np.array(w.pose(2).pos[:2]), 1.0)
print(hashlib.sha256(w.data.qpos.tobytes()).hexdigest())
"""


def test_world_evolves_identically_across_processes() -> None:
    import subprocess
    import sys

    runs = {subprocess.run([sys.executable, "-c", _PROCESS_SCRIPT], capture_output=True, text=True, check=True).stdout
            for _ in range(2)}
    assert len(runs) == 1 and len(next(iter(runs)).strip()) == 64


def test_many_turning_placements_never_wind_the_wrist_into_its_limit() -> None:
    """Each placement turns the block (and wrist) by ~40° the same way; 24 of them add up to
    over two full turns, beyond wrist 3's ±2π range unless the primitive unwinds it."""
    w = World([small(1, "red", 0.45, -0.15), small(2, "blue", 0.55, 0.15)])
    p = Primitives(w)
    spots = [np.array([0.45, -0.15]), np.array([0.55, 0.15])]
    for k in range(24):
        obj = 1 + k % 2
        target = spots[(k // 2 + 1) % 2] if obj == 1 else spots[(k // 2) % 2]
        target = target + np.array([0.0, 0.1 if k % 4 < 2 else -0.1])
        res = p.pick_and_place(np.asarray(w.pose(obj).pos), target, w.pose(obj).yaw + np.radians(40))
        assert res.ok, (k, res)
        assert abs(w.arm_q()[5]) < 2 * np.pi - 0.5


def test_straight_line_is_tracked_within_the_path_tolerance_with_few_ik_solves() -> None:
    """The line is solved at a few path points and joint-interpolated in between: every time sample
    of the plan still puts the tip on the line (within path_tol), for far fewer IK solves than samples."""
    w = World([small(1, "red", 0.5, 0.2)])
    motion = Primitives(w).motion
    calls = {"n": 0}
    solve = motion.ik.solve

    def counted(*a, **k):  # noqa: ANN002, ANN003
        calls["n"] += 1
        return solve(*a, **k)

    motion.ik.solve = counted  # type: ignore[method-assign]
    start = motion.ik.tip_position(w.arm_ctrl())
    end = np.array([0.45, -0.35, 0.12])
    yaw0 = motion.commanded_yaw()
    plan = motion.plan_line(start, end, yaw0, yaw0 + 0.8, motion.cfg.speed)
    assert plan is not None
    assert calls["n"] < len(plan.qs) / 2
    line = end - start
    worst = 0.0
    for q in plan.qs:
        p = motion.ik.tip_position(q)
        a = np.clip(np.dot(p - start, line) / np.dot(line, line), 0.0, 1.0)
        worst = max(worst, float(np.linalg.norm(p - (start + a * line))))
    assert worst <= motion.cfg.path_tol + 1e-4
    np.testing.assert_allclose(motion.ik.tip_position(plan.qs[-1]), end, atol=1e-4)


def test_segments_end_on_target_without_a_converge_wait() -> None:
    """With inertia feed-forward the servos arrive with the reference: a move needs no extra steps."""
    w = World([small(1, "red", 0.5, 0.2)])
    motion = Primitives(w).motion
    target = np.array([0.5, -0.2, 0.25])
    start = motion.ik.tip_position(w.arm_ctrl())
    plan = motion.plan_line(start, target, motion.commanded_yaw(), 0.3, motion.cfg.speed)
    assert plan is not None
    motion.execute(plan)
    stopped, extra = motion.converge(target)
    assert not stopped and extra == 0


def test_time_optimal_timing_is_the_trapezoid_when_the_joints_never_bind() -> None:
    """A path whose joints move uniformly and far below their limits gets the Cartesian
    trapezoid: length / speed + speed / acceleration from rest to rest."""
    from capmj.sim.timing import time_optimal

    length, speed, accel = 0.3, 1.2, 8.0
    s = np.linspace(0.0, 1.0, 301)
    dq = np.tile([0.5, -0.2, 0.1, 0.0, 0.0, 0.3], (len(s), 1))
    timing = time_optimal(s, dq, np.full(len(s), speed / length), accel / length, 100.0, 1000.0)
    assert timing.total == pytest.approx(length / speed + speed / accel, rel=0.01)
    assert timing.slowdown < 1.0
    assert timing.at(np.array([0.0, timing.total]))[[0, 1]].tolist() == pytest.approx([0.0, 1.0])


def test_time_optimal_timing_slows_only_where_a_joint_would_exceed_its_limits() -> None:
    """Where a joint's rate dq/ds is high the path slows to keep that joint at its speed limit;
    elsewhere it runs at the Cartesian cap, so the whole is faster than slowing down uniformly."""
    from capmj.sim.timing import time_optimal

    s = np.linspace(0.0, 1.0, 401)
    rate = 1.0 + 4.0 * np.exp(-((s - 0.5) / 0.08) ** 2)          # joint 0 sweeps fast mid-path
    dq = np.stack([rate] + [np.full(len(s), 0.1)] * 5, axis=1)
    cap, accel, vmax, amax = np.full(len(s), 2.0), 40.0, 3.0, 30.0
    timing = time_optimal(s, dq, cap, accel, vmax, amax)
    t = np.linspace(0.0, timing.total, 20001)
    a = timing.at(t)
    sd = np.gradient(a, t)
    joint_speed = np.interp(a, s, rate) * sd
    assert joint_speed.max() <= vmax * 1.01
    assert sd.max() <= 2.0 * 1.01 and np.diff(a).min() >= 0.0
    assert timing.slowdown == pytest.approx(2.0 / (vmax / rate.max()), rel=1e-3)
    uniform = time_optimal(s, dq, np.full(len(s), vmax / rate.max()), accel, vmax, amax)
    assert timing.total < 0.8 * uniform.total


def test_guarded_descent_brakes_to_the_approach_speed_where_the_slow_part_begins() -> None:
    """One line, fast then slow: the tip never runs faster than the approach speed in its last
    ``slow_last`` metres, runs faster before, and the whole takes less time than a fast line
    that stops plus a slow line would."""
    w = World([small(1, "red", 0.5, 0.2)])
    motion = Primitives(w).motion
    cfg = motion.cfg
    start = motion.ik.tip_position(w.arm_ctrl())
    yaw = motion.commanded_yaw()
    end, slow = start - np.array([0.0, 0.0, 0.25]), 0.05
    plan = motion.plan_line(start, end, yaw, yaw, cfg.speed, slow_last=slow)
    assert plan is not None
    tips = np.array([motion.ik.tip_position(q) for q in plan.qs])
    speed = np.linalg.norm(np.diff(tips, axis=0), axis=1) / plan.dt
    left = np.linalg.norm(tips[1:] - end, axis=1)  # distance to go at each sample's end
    assert speed[left < slow - 1e-3].max() <= cfg.approach_speed * 1.05
    assert speed.max() > 2 * cfg.approach_speed
    np.testing.assert_allclose(tips[-1], end, atol=1e-4)
    total = (len(plan.qs) - 1) * plan.dt
    split = end + np.array([0.0, 0.0, slow])
    fast = motion.plan_line(start, split, yaw, yaw, cfg.speed)
    assert fast is not None
    slow_alone = slow / cfg.approach_speed + cfg.approach_speed / cfg.accel  # rest to rest
    assert total < (len(fast.qs) - 1) * fast.dt + slow_alone


def test_ik_seeded_with_a_neighbours_offset_lands_within_tolerance() -> None:
    """Seeding a solve with the correction of a solve 20 cm away gives the same pose (within the
    solver's 0.1 mm tolerance) as solving from the analytic solution alone."""
    w = World([small(1, "red", 0.5, 0.2)])
    ik = Primitives(w).motion.ik
    q0 = w.arm_ctrl()
    first = ik.solve(np.array([0.4, -0.2, 0.2]), 0.3, q0)
    assert first.q is not None and first.offset is not None
    target = np.array([0.55, -0.05, 0.2])
    seeded, plain = ik.solve(target, 0.3, first.q, offset=first.offset), ik.solve(target, 0.3, first.q)
    assert seeded.q is not None and plain.q is not None
    for q in (seeded.q, plain.q):
        np.testing.assert_allclose(ik.tip_position(q), target, atol=1e-4)
    np.testing.assert_allclose(seeded.q, plain.q, atol=1e-3)


def test_a_two_line_move_rounds_its_corner_within_the_blend_radius() -> None:
    """Up then across as one move: the arm does not stop at the corner, so it arrives in fewer
    steps than two separate moves, and the tip never leaves the two lines by more than the blend
    radius (plus servo tracking)."""
    def run(blended: bool) -> tuple[int, list[np.ndarray]]:
        w = World([small(1, "red", 0.5, 0.2)])
        motion = Primitives(w).motion
        tips: list[np.ndarray] = []
        w.add_frame_listener(lambda world: tips.append(world.tip_pose()[0].copy()), 1)
        yaw = motion.commanded_yaw()
        start = motion.ik.tip_position(w.arm_ctrl())
        corner, end = start + np.array([0.0, 0.0, 0.1]), start + np.array([0.0, -0.3, 0.1])
        if blended:
            status, steps, _ = motion.move_through([(corner, yaw), (end, yaw)])
        else:
            (status, a), (_, b) = motion.move_to(corner, yaw), motion.move_to(end, yaw)
            steps = a + b
        assert status == "ok"
        np.testing.assert_allclose(w.tip_pose()[0], end, atol=motion.cfg.track_tol)
        return steps, tips

    separate, _ = run(False)
    steps, tips = run(True)
    assert steps < separate - 20
    w = World([small(1, "red", 0.5, 0.2)])
    start = Primitives(w).motion.ik.tip_position(w.arm_ctrl())
    corner = start + np.array([0.0, 0.0, 0.1])
    off = [min(np.hypot(p[0] - start[0], p[1] - start[1]),                     # the vertical line
               np.hypot(p[0] - start[0], p[2] - corner[2])) for p in tips]     # the horizontal one
    assert max(off) <= Primitives(w).cfg.blend + 2e-3
    assert max(off) > 2e-3  # it did cut the corner


def test_object_boxes_bound_every_geom_of_each_object_tightly() -> None:
    """All objects' boxes at once, a bowl's many geoms included: each box holds every corner of
    its object's geoms' own (rotated) boxes and touches the extreme ones."""
    import itertools

    w = World([small(1, "red", 0.5, 0.0, yaw=0.4), ObjectSpec(2, "bowl", "blue", (0.45, 0.25, BOWL_HEIGHT / 2))])
    w.settle()
    ids, lo, hi = w.object_boxes()
    assert ids.tolist() == [1, 2]
    m, d = w.model, w.data
    for k, obj in enumerate(ids):
        corners = []
        for g in np.flatnonzero(w.geom_obj == obj):
            rot = d.geom_xmat[g].reshape(3, 3)
            centre, half = m.geom_aabb[g, :3], m.geom_aabb[g, 3:]
            corners += [d.geom_xpos[g] + rot @ (centre + np.array(s) * half) for s in itertools.product((-1, 1), repeat=3)]
        pts = np.array(corners)
        np.testing.assert_allclose(pts.min(axis=0), lo[k], atol=1e-12)
        np.testing.assert_allclose(pts.max(axis=0), hi[k], atol=1e-12)
    assert np.array_equal(w.aabb(2)[1], hi[1]) and w.top_z(1) == hi[0, 2]


def test_pose_quat_xyzw_reorders_mujocos_quaternion_and_the_old_name_warns() -> None:
    from capmj.sim.state import Pose

    p = Pose((0.0, 0.0, 0.0), (0.5, 0.1, 0.2, 0.3))  # w, x, y, z as in MuJoCo
    assert p.quat_xyzw == (0.1, 0.2, 0.3, 0.5)
    with pytest.warns(DeprecationWarning, match="quat_xyzw"):
        assert p.xquat == p.quat_xyzw
