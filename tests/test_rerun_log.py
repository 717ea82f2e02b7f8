"""The rerun episode log: a real oracle episode written to .rrd, read back offline, and replayed."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rerun")
from rerun.chunk import RrdReader  # noqa: E402

from capmj.agents.oracle import OracleAgent  # noqa: E402
from capmj.log import record_episode  # noqa: E402
from capmj.tasks.protocol import make_scene  # noqa: E402
from capmj.tasks.registry import get_task  # noqa: E402

TASK, SEED = "put-block-into-matching-bowl", 10001


def _read(path: Path) -> dict[str, list]:
    """entity path -> list of (is_static, record batch)."""
    out: dict[str, list] = {}
    for c in RrdReader(str(path)).stream().to_chunks():
        out.setdefault(c.entity_path, []).append((c.is_static, c.to_record_batch()))
    return out


def _column(chunks: list, name: str, static: bool | None = None) -> list:
    vals = []
    for is_static, rb in chunks:
        if static is not None and is_static != static:
            continue
        if name in rb.schema.names:
            vals.extend(rb.column(name).to_pylist())
    return vals


def _seconds(rb) -> list[float]:
    """The sim_time column in seconds (pyarrow cannot turn every ns duration into a timedelta)."""
    import pyarrow as pa

    if "sim_time" not in rb.schema.names:
        return []
    return [v / 1e9 for v in rb.column("sim_time").cast(pa.int64()).to_pylist()]


@pytest.fixture(scope="module")
def episode(tmp_path_factory):
    path = tmp_path_factory.mktemp("rrd") / "ep.rrd"
    task = get_task(TASK)
    result = record_episode(task, SEED, OracleAgent(), path)
    return path, result, make_scene(task, SEED)


def test_rrd_holds_world_objects_texts_timelines_and_summary(episode):
    path, result, scene = episode
    assert result.success and result.rrd == str(path) and result.primitives >= 1
    ent = _read(path)

    # every object: static shape with its colour, and transforms over time
    for o in scene.objects:
        chunks = ent[f"/world/objects/{o.body}"]
        static_cols = {n for s, rb in chunks if s for n in rb.schema.names}
        assert static_cols & {"Boxes3D:half_sizes", "Cylinders3D:radii", "Ellipsoids3D:half_sizes"}, o
        trans = _column(chunks, "Transform3D:translation", static=False)
        assert trans, f"no transforms for {o.body}"
        first = np.asarray(trans[0][0])
        assert np.allclose(first[:2], o.pos[:2], atol=0.01), (o, first)
    # a block the oracle moved has several poses, ending where the primitive put it
    moved = [o for o in scene.objects if not o.fixed]
    finals = {}
    summary_chunks = ent["/summary_json"]
    summary = json.loads(_column(summary_chunks, "TextDocument:text")[0][0])
    for p in summary["primitive_log"]:
        finals[p["obj_id"]] = p["final_pos"]
    assert finals, "the oracle logged no primitive"
    for o in moved:
        if o.obj_id not in finals:
            continue
        trans = _column(ent[f"/world/objects/{o.body}"], "Transform3D:translation", static=False)
        assert len(trans) > 3
        last = np.asarray(trans[-1][0])
        assert np.linalg.norm(last[:2] - np.asarray(finals[o.obj_id][:2])) < 0.02

    # robot links move over time
    robot = _column(ent["/world/robot"], "Points3D:positions", static=False)
    assert len(robot) > 10 and len(robot[0]) >= 7

    # sim_time and primitive timelines on the frames; the primitive log covers 1..n
    for is_static, rb in ent[f"/world/objects/{moved[0].body}"]:
        if not is_static:
            assert {"sim_time", "primitive"} <= set(rb.schema.names)
    prim_idx = sorted(set(_column(ent["/world/primitives/targets"], "primitive")))
    assert prim_idx == list(range(1, result.primitives + 1))
    secs = [t for _, rb in ent["/world/robot"] for t in _seconds(rb)]
    assert secs == sorted(secs) and secs[-1] > 1.0

    # goal and verdict texts
    goal = _column(ent["/text/goal"], "TextDocument:text")
    verdict = _column(ent["/text/verdict"], "TextDocument:text")
    assert goal[0][0] == result.goal
    assert verdict[-1][0].startswith("SUCCESS")

    # the summary: markdown at /summary, JSON at /summary_json, matching the result
    assert summary["task"] == TASK and summary["seed"] == SEED and summary["success"] is True
    assert summary["primitives"] == result.primitives == len(summary["primitive_log"])
    assert summary["diagnostics"] == list(result.diagnostics)
    md = _column(ent["/summary"], "TextDocument:text")[0][0]
    assert TASK in md and "SUCCESS" in md

    # the viewer layout travels in the file
    assert RrdReader(str(path)).blueprints(), "no blueprint stored in the .rrd"


def test_replay_prints_summary_from_file(episode):
    path, result, _ = episode
    proc = subprocess.run([sys.executable, "-m", "capmj.replay", str(path)], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    assert f"task:        {TASK}" in out
    assert f"seed:        {SEED}" in out
    assert "verdict:     SUCCESS" in out
    assert out.count("  #") == result.primitives  # one line per primitive
    js = subprocess.run([sys.executable, "-m", "capmj.replay", str(path), "--json"], capture_output=True, text=True,
                        timeout=120)
    assert json.loads(js.stdout)["seed"] == SEED


def test_replay_rejects_non_rrd(tmp_path):
    bad = tmp_path / "x.rrd"
    bad.write_text("not a rerun file")
    from capmj.replay.cli import main

    assert main([str(bad)]) == 2
    assert main([str(tmp_path / "missing.rrd")]) == 2


def test_recorder_without_world_keeps_time_monotonic_and_texts_under_text(tmp_path):
    from capmj.log import RerunRecorder
    from capmj.replay import read_episode

    p = tmp_path / "r.rrd"
    rec = RerunRecorder(p, task="t", seed=1, agent="a")
    pose = ((0.5, 0.0, 0.02), (1.0, 0.0, 0.0, 0.0))
    for t in (0.0, 0.05, 0.10):
        rec.frame(t, {"obj1": ((0.5, 0.0, t), pose[1])})
    rec.text("llm/planner/prompt", "objects = [...]")
    rec.text("llm/planner/stale", "a time in the past must not look like a reset", time=0.02)
    for t in (0.0, 0.05):  # a reset to the initial state (re-plan): raw time goes back
        rec.frame(t, {"obj1": ((0.6, 0.0, t), pose[1])})
    rec.primitive(1, 0.05, {"ok": False, "status": "no_grip", "obj_id": None, "pick": (0.5, 0, 0.02),
                            "place": (0.6, 0, 0.02), "final_pos": None, "attempt": 1})
    rec.finish({"task": "t", "seed": 1, "agent": "a", "success": False, "progress": 0.0, "primitives": 1})
    rec.close()
    log = read_episode(p)
    assert log.texts["llm/planner/prompt"] == ["objects = [...]"]
    assert log.summary["primitive_log"][0]["status"] == "no_grip"
    ent = _read(p)
    times = [t for _, rb in ent["/world/objects/obj1"] for t in _seconds(rb)]
    # the reset continues the timeline one frame period (0.05 s) after the last frame
    assert times == pytest.approx([0.0, 0.05, 0.10, 0.15, 0.20])


def test_camera_images_logged_and_exported(tmp_path):
    pytest.importorskip("capmj.sim.cameras")
    from capmj.replay import export_frames, read_episode

    p = tmp_path / "img.rrd"
    res = record_episode(get_task(TASK), SEED, OracleAgent(), p, images=True)
    log = read_episode(p)
    if log.summary.get("image_error"):
        pytest.skip(f"no rendering here: {log.summary['image_error']}")
    assert res.success
    # initial images (primitive 0) + one set per primitive, for each of the 3 cameras, rgb + depth
    assert log.summary["images_logged"] == 2 * 3 * (res.primitives + 1)
    frames = export_frames(p, tmp_path / "frames")
    names = {f.name for f in frames}
    assert "front_rgb_p000.png" in names and f"front_depth_p{res.primitives:03d}.png" in names
    from PIL import Image

    depth = Image.open(tmp_path / "frames" / "front_depth_p000.png")
    assert depth.mode.startswith("I") and 300 < depth.getextrema()[0] < 5000  # millimetres
