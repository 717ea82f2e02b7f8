"""Motion that plans the arm's links (#48 item 1): a tower of six blocks between two points, the
straight motion of before (``plan_collisions`` off) against the checked and planned one; a place
target inside a fixture's wall; the same planned path in two processes."""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys

import numpy as np
import pytest

from capmj.bench.failures import _error_label
from capmj.errors import MotionPlanningError
from capmj.sim.motion_config import MotionConfig
from capmj.sim.objects import BLOCK_SIZES, ObjectSpec
from capmj.sim.primitives import Primitives
from capmj.sim.world import World

KNOCKED_M = 0.05
"""An object that moved this far was knocked (a block resting undisturbed moves < 1 mm)."""
UNDISTURBED_M = 0.005
"""The issue's threshold: an object moved more than this was disturbed by the harness."""


def tower_world(tower_xy: tuple[float, float], size: str, with_block_at: tuple[float, float] | None) -> World:
    """Six blocks stacked at ``tower_xy`` (ids 2..7), and optionally a small block to pick (id 1)."""
    h = BLOCK_SIZES[size]
    objs = [ObjectSpec(2 + k, "block", "blue", (tower_xy[0], tower_xy[1], h / 2 + k * h), size=size) for k in range(6)]
    if with_block_at is not None:
        objs.insert(0, ObjectSpec(1, "block", "red", (with_block_at[0], with_block_at[1], 0.02), size="small"))
    w = World(objs)
    w.settle()
    return w


def tower_moved(w: World, before: dict[int, np.ndarray]) -> float:
    w.settle(1000)
    return max(float(np.linalg.norm(np.asarray(w.pose(i).pos) - before[i])) for i in before)


def tower_poses(w: World) -> dict[int, np.ndarray]:
    return {i: np.asarray(w.pose(i).pos).copy() for i in range(2, 8)}


A, B = np.array([0.35, -0.25, 0.12]), np.array([0.35, 0.25, 0.12])
"""A move of the tool across a tower of six small blocks at (0.35, 0), 12 cm above the table."""


def move_across(plan: bool) -> tuple[World, Primitives, float]:
    w = tower_world((0.35, 0.0), "small", None)
    before = tower_poses(w)
    arm = Primitives(w, MotionConfig(plan_collisions=plan), seed=7)
    assert arm.motion.move_to_pose(A, 0.0)[0] == "ok"
    assert arm.motion.move_to_pose(B, 0.0)[0] == "ok"
    return w, arm, tower_moved(w, before)


def test_a_move_across_a_tower_knocks_it_unplanned_and_goes_around_it_planned() -> None:
    w, _, moved = move_across(plan=False)
    assert moved > KNOCKED_M, "the scene must really knock the tower on the straight path"
    w, arm, moved = move_across(plan=True)
    assert moved < UNDISTURBED_M
    assert np.linalg.norm(w.tip_pose()[0] - B) < 0.005  # it still got there
    planned = [p for p in arm.motion.paths if p.planned]
    assert planned, "the straight line was blocked, so the move must have been planned"
    tips = np.array(planned[-1].tip)
    assert tips[:, 1].min() < -0.05 and tips[:, 1].max() > 0.05  # the path crosses the tower's line...
    assert np.min(np.hypot(tips[:, 0] - 0.35, tips[:, 1]) + (tips[:, 2] > 0.3)) > 0.03  # ...not through it


def test_pick_and_place_past_a_tower_never_knocks_it() -> None:
    """Six big blocks stacked between pick and place, next to the place point: the straight
    primitive's wrist sweeps the tower down as it descends; with planning on the arm takes
    another posture for the descent (its wrist on the other side) and places the block with
    the tower standing."""
    pick, place = np.array([0.35, -0.3]), np.array([0.35, 0.3])
    results = {}
    for plan in (False, True):
        w = tower_world((0.35, 0.12), "big", (0.35, -0.3))
        before = tower_poses(w)
        res = Primitives(w, MotionConfig(plan_collisions=plan)).pick_and_place(pick, place)
        results[plan] = (res, tower_moved(w, before))
    assert results[False][0].ok and results[False][1] > KNOCKED_M
    res, moved = results[True]
    assert moved < UNDISTURBED_M
    assert res.ok and np.linalg.norm(np.asarray(res.final_pos)[:2] - place) < 0.01


def test_a_place_target_inside_a_fixture_wall_fails_as_motion() -> None:
    w = World([ObjectSpec(1, "block", "red", (0.5, 0.0, 0.02), size="small"),
               ObjectSpec(2, "fixture", "blue", (0.5, 0.2, 0.02))])
    w.settle()
    arm = Primitives(w)
    wall = (0.5, 0.2 - 0.028, 0.02)  # the long wall's centre line (capmj.sim.shapes.FIXTURE_WALLS)
    res = arm.pick_and_place(np.array([0.5, 0.0]), np.array(wall))
    assert res.status == "no_path"
    assert "inside" in res.message and "fixture with obj_id 2" in res.message
    assert np.linalg.norm(np.asarray(w.pose(1).pos)[:2] - [0.5, 0.0]) < 0.005  # put back, not dropped on the wall
    assert _error_label("MotionPlanningError", None) == "motion"
    with pytest.raises(MotionPlanningError):  # a low-level move there is refused the same way
        arm.motion.move_to_pose(np.array([0.517, 0.172, 0.03]), 0.0)


_CHILD = """
import hashlib, json, sys
sys.path.insert(0, {tests!r})
from test_motion_planning import move_across
w, arm, moved = move_across(plan=True)
paths = [p.joints for p in arm.motion.paths if p.planned]
print(json.dumps([hashlib.sha256(p.tobytes()).hexdigest() for p in paths]))
"""


def test_the_same_seed_plans_the_same_path_in_two_processes() -> None:
    import os

    code = _CHILD.format(tests=os.path.dirname(__file__))
    outs = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                           env={**os.environ, "PYTHONHASHSEED": str(k)}).stdout.strip().splitlines()[-1]
            for k in (1, 2)]
    assert outs[0] == outs[1]
    assert json.loads(outs[0])  # there was a planned path to compare
    _, arm, _ = move_across(plan=True)
    here = [hashlib.sha256(p.joints.tobytes()).hexdigest() for p in arm.motion.paths if p.planned]
    assert json.loads(outs[0]) == here


def test_planned_paths_are_drawn_as_lines_in_the_rrd(tmp_path) -> None:
    pytest.importorskip("rerun")
    import warnings

    from rerun.chunk import RrdReader

    from capmj.log.recorder import RerunRecorder

    w, arm, _ = move_across(plan=True)
    lines = [p.tip for p in arm.motion.paths if p.planned]
    rec = RerunRecorder(tmp_path / "e.rrd", task="t", seed=1, agent="a")
    rec.primitive(1, 1.0, {"pick": tuple(A), "place": tuple(B), "status": "ok", "ok": True, "planned": lines})
    rec.primitive(2, 2.0, {"pick": tuple(B), "place": tuple(A), "status": "ok", "ok": True, "planned": ()})
    rec.close()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        chunks = [c for c in RrdReader(str(tmp_path / "e.rrd")).stream().to_chunks()
                  if c.entity_path.endswith("/planned")]
    assert {c.entity_path for c in chunks} == {"/world/primitives/1/planned"}
    batch = chunks[0].to_record_batch()
    name = next(n for n in batch.schema.names if n.lower().endswith("strips"))
    assert len(batch.column(name).to_pylist()[0]) == len(lines)
