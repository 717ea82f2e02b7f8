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
    start = motion.ik.tip_position(w.data.ctrl[:6].copy())
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
    start = motion.ik.tip_position(w.data.ctrl[:6].copy())
    plan = motion.plan_line(start, target, motion.commanded_yaw(), 0.3, motion.cfg.speed)
    assert plan is not None
    motion.execute(plan)
    stopped, extra = motion.converge(target)
    assert not stopped and extra == 0


def test_guarded_descent_profile_brakes_to_the_approach_speed_before_the_slow_part() -> None:
    """One line, fast then slow: the speed where the slow part begins is the approach speed, the
    slow part never runs faster, the line ends at rest on its end, and no limit is exceeded."""
    from capmj.sim.motion import Motion

    length, slow, speed, slow_speed, accel = 0.2, 0.05, 1.2, 0.25, 8.0
    total, s = Motion._profile(length, speed, accel, slow, slow_speed)
    t = np.linspace(0.0, total, 20001)
    x = s(t) * length
    v = np.gradient(x, t)
    assert x[0] == 0.0 and x[-1] == pytest.approx(length)
    assert np.all(np.diff(x) >= -1e-12) and v.max() <= speed + 1e-3
    assert np.interp(length - slow, x, v) == pytest.approx(slow_speed, abs=2e-3)
    assert v[x > length - slow + 1e-4].max() <= slow_speed + 2e-3
    assert np.abs(np.gradient(v, t)[5:-5]).max() <= accel * 1.01
    # a single-speed line reaches the same end in less time than fast + stop + slow would
    fast_total, _ = Motion._profile(length - slow, speed, accel)
    slow_total, _ = Motion._profile(slow, slow_speed, accel)
    assert total < fast_total + slow_total


def test_ik_seeded_with_a_neighbours_offset_lands_within_tolerance() -> None:
    """Seeding a solve with the correction of a solve 20 cm away gives the same pose (within the
    solver's 0.1 mm tolerance) as solving from the analytic solution alone."""
    w = World([small(1, "red", 0.5, 0.2)])
    ik = Primitives(w).motion.ik
    q0 = w.data.ctrl[:6].copy()
    first = ik.solve(np.array([0.4, -0.2, 0.2]), 0.3, q0)
    assert first.q is not None and first.offset is not None
    target = np.array([0.55, -0.05, 0.2])
    seeded, plain = ik.solve(target, 0.3, first.q, offset=first.offset), ik.solve(target, 0.3, first.q)
    assert seeded.q is not None and plain.q is not None
    for q in (seeded.q, plain.q):
        np.testing.assert_allclose(ik.tip_position(q), target, atol=1e-4)
    np.testing.assert_allclose(seeded.q, plain.q, atol=1e-3)
