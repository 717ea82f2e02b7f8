"""What an rgbd episode perceived, in its ``.rrd``: a real episode recorded and read back.

The reference plan runs with ``--perception rgbd`` on a real scene; the log must hold one view of
detection boxes per perception call (the first one and one after each pick-and-place), labelled
with the names the plan was given and their confidence, lying on the true objects, and one line
of errors per call that says what the episode's record says.  The judging of a box (right /
wrong / false) is tested on hand-made detections, where the answer is known.
"""

from __future__ import annotations

import ast
import json
import math
import re

import numpy as np
import pytest

pytest.importorskip("rerun")
from test_rerun_log import _column, _read  # noqa: E402

from capmj.agents.api.perception_audit import footprint_box, perceived_boxes  # noqa: E402
from capmj.agents.reference import ReferenceAgent  # noqa: E402
from capmj.log.paths import DETECTIONS, PERCEPTION_LOG  # noqa: E402
from capmj.log.perception3d import MATCH_COLORS, error_line  # noqa: E402
from capmj.perception import Detection  # noqa: E402
from capmj.perception.score import TrueObject, score  # noqa: E402
from capmj.perception.track import Tracker  # noqa: E402
from capmj.runner import record_episode  # noqa: E402
from capmj.tasks.protocol import make_scene  # noqa: E402
from capmj.tasks.registry import get_task  # noqa: E402

TASK, SEED = "put-block-into-matching-bowl", 10001
_LABEL = re.compile(r"^((?:movable|fixed) .+ with obj_id \d+) (\d\.\d\d)$")


def _rgb(color: list[int]) -> int:
    return int.from_bytes(bytes([*color, 255]), "big")


@pytest.fixture(scope="module")
def rgbd_episode(tmp_path_factory):
    path = tmp_path_factory.mktemp("rrd") / "rgbd.rrd"
    task = get_task(TASK)
    result = record_episode(task, SEED, ReferenceAgent(perception="rgbd"), path)
    return path, result, make_scene(task, SEED)


def test_every_perception_call_is_drawn_with_names_confidence_and_errors(rgbd_episode):
    path, result, scene = rgbd_episode
    assert result.success and result.primitives >= 2
    calls = result.perception.calls
    assert len(calls) == result.primitives + 1  # the first view, then one after each pick-and-place
    ent = _read(path)

    labels = _column(ent[DETECTIONS], "Boxes3D:labels", static=False)
    centers = _column(ent[DETECTIONS], "Boxes3D:centers", static=False)
    colors = _column(ent[DETECTIONS], "Boxes3D:colors", static=False)
    assert [len(v) for v in labels] == [c.detections for c in calls]
    assert [len(v) for v in centers] == [c.detections for c in calls]

    # the first view's labels are the names the plan was handed, each with a confidence in [0, 1]
    plan = _column(ent["/text/reference/plan"], "TextDocument:text")[0][0]
    names = ast.literal_eval(next(line for line in plan.splitlines() if line.startswith("objects = "))[10:])
    parsed = [_LABEL.match(s) for s in labels[0]]
    assert all(parsed), labels[0]
    assert [m.group(1) for m in parsed] == names
    assert all(0.0 <= float(m.group(2)) <= 1.0 for m in parsed)
    # ... one per true object, each box on its object (xy), all judged right on this clean scene
    assert len(names) == len(scene.objects)
    true_xy = np.array([o.pos[:2] for o in scene.objects])
    for c in centers[0]:
        assert np.min(np.linalg.norm(true_xy - np.asarray(c[:2]), axis=1)) < 0.005
    assert set(colors[0]) == {_rgb(MATCH_COLORS["right"])}

    # one line of errors per call, the same figures as the episode's record
    lines = [v[0] for v in _column(ent[PERCEPTION_LOG], "TextLog:text", static=False)]
    assert lines == [error_line(c) for c in calls]
    assert lines[0].startswith(f"attempt 1 reset: {len(names)} detections of {len(names)} objects, missed 0")
    summary = json.loads(_column(ent["/summary_json"], "TextDocument:text")[0][0])
    assert summary["perception_views"] == len(calls)


def test_replay_names_the_perception_views(rgbd_episode, capsys):
    from capmj.replay.cli import main

    path, result, _ = rgbd_episode
    assert main([str(path)]) == 0
    assert f"perception views: {len(result.perception.calls)} (/world/perception/detections" in capsys.readouterr().out


def test_a_state_mode_episode_draws_no_detections(tmp_path):
    path = tmp_path / "state.rrd"
    result = record_episode(get_task(TASK), SEED, ReferenceAgent(perception="state"), path)
    assert result.success and result.perception is None
    ent = _read(path)
    assert DETECTIONS not in ent and PERCEPTION_LOG not in ent


def _block(color: str, x: float, y: float, yaw: float = 0.0) -> Detection:
    e = 0.02 * (abs(math.cos(yaw)) + abs(math.sin(yaw)))  # a small block (4 cm) turned by yaw
    return Detection("block", color, "small", 1.0, (x, y, 0.02), yaw,
                     ((x - e, y - e, 0.0), (x + e, y + e, 0.04)), 0.9)


def test_boxes_are_judged_right_wrong_or_false_against_the_truth():
    truth = [TrueObject("block", "red", "small", (0.40, 0.00, 0.02), 0.3),
             TrueObject("block", "blue", "small", (0.50, 0.10, 0.02), 0.0)]
    seen = [_block("red", 0.401, 0.0, 0.3),    # right
            _block("green", 0.50, 0.10),       # on the blue block, wrong colour
            _block("red", 0.60, -0.10)]        # nothing there
    tracked = Tracker.start(seen).objects
    boxes = perceived_boxes(tracked, score([t.detection for t in tracked], truth), [7, 9])
    by_name = {b.name: b for b in boxes}
    assert [b.match for b in boxes] == [by_name[t.name].match for t in tracked]
    status = {t.detection.color + str(round(t.detection.position[0], 2)): by_name[t.name] for t in tracked}
    assert (status["red0.4"].match, status["red0.4"].truth) == ("right", 7)
    assert (status["green0.5"].match, status["green0.5"].truth) == ("wrong", 9)
    assert (status["red0.6"].match, status["red0.6"].truth) == ("false", None)
    # a turned square's box is its footprint with its yaw, not its larger axis-aligned box
    centre, half, yaw = footprint_box(_block("red", 0.4, 0.0, 0.3))
    assert centre == pytest.approx((0.4, 0.0, 0.02)) and yaw == pytest.approx(0.3)
    assert half == pytest.approx((0.02, 0.02, 0.02))
