"""The rerun episode log: a real failed episode written to .rrd, read back offline, and replayed.

The failing agent puts the first block into a wrong bowl and the second into the right one, with
real physics, so the file must show one failing object (with its diagnostic and an arrow to its
bowl), one red and one green "final" marker, and the real robot.
"""

from __future__ import annotations

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rerun")
from rerun.chunk import RrdReader  # noqa: E402

from capmj.log.geometry import GRIP_COLOR  # noqa: E402
from capmj.log.verdict3d import FAIL_COLOR, OK_COLOR  # noqa: E402
from capmj.runner import record_episode  # noqa: E402
from capmj.sim.robot import ARM_BODIES  # noqa: E402
from capmj.tasks.protocol import make_scene  # noqa: E402
from capmj.tasks.registry import get_task  # noqa: E402

TASK, SEED = "put-block-into-matching-bowl", 10001
MAX_BYTES = 250_000


class WrongBowlAgent:
    """Block 1 of the task's pairs into another bowl, block 2 into its own bowl."""

    name = "wrong-bowl"
    model = None

    def act(self, ctx) -> None:
        (b1, w1), (b2, w2) = ctx.scene.info["pairs"][:2]
        other = next(w for w in ctx.scene.info["bowls"] if w != w1)
        ctx.pick_and_place(ctx.world.pose(b1).pos, np.add(ctx.world.pose(other).pos, [0, 0, 0.03]))
        ctx.pick_and_place(ctx.world.pose(b2).pos, np.add(ctx.world.pose(w2).pos, [0, 0, 0.03]))


def _read(path: Path, store=None) -> dict[str, list]:
    """entity path -> list of (is_static, record batch)."""
    out: dict[str, list] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reader = RrdReader(str(path))
        for c in reader.stream(store=store(reader) if store else None).to_chunks():
            out.setdefault(c.entity_path, []).append((c.is_static, c.to_record_batch()))
    return out


def _column(chunks: list, name: str, static: bool | None = None) -> list:
    vals = []
    for is_static, rb in chunks:
        if (static is None or is_static == static) and name in rb.schema.names:
            vals.extend(rb.column(name).to_pylist())
    return vals


def _seconds(chunks: list, name: str) -> list[float]:
    """sim_time (s) of the rows that hold component ``name``."""
    import pyarrow as pa

    out = []
    for is_static, rb in chunks:
        if not is_static and name in rb.schema.names:
            t = rb.column("sim_time").cast(pa.int64()).to_pylist()
            out += [v / 1e9 for v, x in zip(t, rb.column(name).to_pylist()) if x is not None]
    return out


def _views(path: Path) -> dict[str, str]:
    """name -> origin of the views in the file's blueprint."""
    ent = _read(path, store=lambda r: r.blueprints()[0])
    views = {}
    for chunks in ent.values():
        names = _column(chunks, "ViewBlueprint:display_name")
        origins = _column(chunks, "ViewBlueprint:space_origin")
        for n, o in zip(names, origins):
            views[n[0]] = o[0]
    return views


@pytest.fixture(scope="module")
def failed(tmp_path_factory):
    path = tmp_path_factory.mktemp("rrd") / "failed.rrd"
    task = get_task(TASK)
    result = record_episode(task, SEED, WrongBowlAgent(), path)
    return path, result, make_scene(task, SEED)


def test_record_episode_always_logs_and_a_worker_runs_an_unlogged_job_with_run_episode(failed):
    """record_episode has one contract (it logs to its path); an episode without a log is
    run_episode, which the bench worker calls for a job without an rrd (--no-log)."""
    from capmj.agents.oracle import OracleAgent
    from capmj.bench.worker import AgentSpec, Job, Worker
    from capmj.runner import run_episode

    path, result, _ = failed
    assert result.rrd == str(path) and path.stat().st_size > 0
    with pytest.raises(TypeError, match="run_episode"):
        record_episode(get_task(TASK), SEED, WrongBowlAgent(), None)  # type: ignore[arg-type]
    unlogged = Worker(AgentSpec("oracle", {}, False)).run_job(Job(TASK, SEED))
    direct = run_episode(get_task(TASK), SEED, OracleAgent()).to_dict()
    assert unlogged["rrd"] is None and unlogged["success"]
    assert {k: unlogged[k] for k in ("success", "progress", "primitives", "sim_s")} == {
        k: direct[k] for k in ("success", "progress", "primitives", "sim_s")}


def test_failed_episode_shows_the_verdict_in_3d(failed):
    path, result, scene = failed
    (b1, w1), (b2, _) = scene.info["pairs"][:2]
    assert not result.success and result.primitives == 2
    assert result.diagnostics and f"block {b1} " in result.diagnostics[0]
    ent = _read(path)

    # the failing block: a red outline labelled with its diagnostic, static, following the block
    outline = ent[f"/world/objects/obj{b1}/verdict"]
    assert all(s for s, _ in outline)
    label = _column(outline, "Points3D:labels")[0][0]
    assert label.replace("\n", " ") == result.diagnostics[0]
    assert _column(outline, "Boxes3D:colors")[0][0] == int.from_bytes(bytes([*FAIL_COLOR, 255]), "big")
    assert _column(outline, "Boxes3D:half_sizes")[0][0][0] > scene.by_id(b1).half_extents[0]
    assert f"/world/objects/obj{b2}/verdict" not in ent  # the block in its bowl is not failing
    # its bowl and the other goal block have their names shown
    assert _column(ent[f"/world/objects/obj{w1}/name"], "Points3D:labels")[0] == [f"{scene.by_id(w1).color} bowl {w1}"]
    assert f"/world/objects/obj{b2}/name" in ent

    # an arrow from where the block ended to where the task wants it (inside its bowl)
    origin = np.asarray(_column(ent["/world/verdict/arrows"], "Arrows3D:origins")[0][0])
    vector = np.asarray(_column(ent["/world/verdict/arrows"], "Arrows3D:vectors")[0][0])
    final_b1 = next(p["final_pos"] for p in json.loads(_column(ent["/summary_json"], "TextDocument:text")[0][0])
                    ["primitive_log"] if p["obj_id"] == b1)
    assert np.allclose(origin[:2], final_b1[:2], atol=0.01)
    assert np.allclose((origin + vector)[:2], scene.by_id(w1).pos[:2], atol=0.005)

    # every primitive keeps its own pick/place markers, logged when it started (before it ended)
    summary = json.loads(_column(ent["/summary_json"], "TextDocument:text")[0][0])
    for p in summary["primitive_log"]:
        k = p["index"]
        markers = ent[f"/world/primitives/{k}"]
        pts = np.asarray(_column(markers, "Points3D:positions")[0])
        assert np.allclose(pts, [p["pick"], p["place"]], atol=1e-5)
        (start,) = _seconds(markers, "Points3D:positions")
        assert start == pytest.approx(p["start"], abs=1e-6) and start < p["time"] - 0.5
        assert set(_column(markers, "primitive")) == {k}
        # the "final" marker: red when the moved object's goal condition fails at the end, else green
        final = ent[f"/world/primitives/{k}/final"]
        want = FAIL_COLOR if p["obj_id"] == b1 else OK_COLOR
        assert _column(final, "Boxes3D:colors")[0][0] == int.from_bytes(bytes([*want, 255]), "big")
        assert _seconds(final, "Boxes3D:centers") == [pytest.approx(p["time"])]
    assert summary["failing_objects"] == [b1] and summary["verdict_arrows"] == 1


def test_robot_meshes_link_transforms_and_grip(failed):
    path, _, _ = failed
    ent = _read(path)
    for link in ("base", *ARM_BODIES):
        chunks = ent[f"/world/robot/{link}"]
        faces = _column(chunks, "Mesh3D:triangle_indices", static=True)
        normals = _column(chunks, "Mesh3D:vertex_normals", static=True)
        assert len(faces[0]) >= 20 and len(normals[0]) > 0, link
    for link in ARM_BODIES:  # moving links: a transform per logged frame
        trans = _column(ent[f"/world/robot/{link}"], "Transform3D:translation", static=False)
        assert len(trans) > 20, link
    # the suction tool rides on the wrist with one static transform; its cup reaches the tip
    tool = ent["/world/robot/wrist_3_link/suction"]
    assert _column(tool, "Transform3D:translation", static=True) and not _column(tool, "Transform3D:translation", static=False)
    cup = ent["/world/robot/wrist_3_link/suction/cup"]
    assert _column(cup, "Cylinders3D:lengths", static=True)[0][0] > 0.1
    # the cup turns orange while it grips (twice: one per primitive) and back
    colors = [c[0] for c in _column(cup, "Cylinders3D:colors", static=False)]
    grip = int.from_bytes(bytes([*GRIP_COLOR, 255]), "big")
    assert colors.count(grip) == 2 and colors[0] != grip and colors[-1] != grip


def test_size_without_images_and_summary_order(failed):
    path, result, _ = failed
    assert path.stat().st_size <= MAX_BYTES
    md = _column(_read(path)["/summary"], "TextDocument:text")[0][0]
    assert md.startswith("# FAILURE") and md.index("## Diagnostics") < md.index("## Primitives")
    assert result.diagnostics[0] in md


def test_attempt_documents_layout_say_and_static_texts(tmp_path, failed):
    """Texts as the LLM agent sends them become one reading-order document per attempt."""
    from capmj.log import RerunRecorder
    from capmj.replay import read_episode

    p = tmp_path / "llm.rrd"
    rec = RerunRecorder(p, task="t", seed=1, agent="llm", model="m")
    rec.text("goal", "stack the blocks")
    code = "a = 1\nb = 2\nput_first_on_second(a, b)\nprint('done')\n"
    rec.text("llm/attempt1/planner/1/prompt", "PROMPT-1", time=0.1)
    rec.text("llm/attempt1/planner/1/completion", "COMPLETION-1", time=0.2)
    rec.text("llm/attempt1/parse_obj_name/1/prompt", "HELPER-PROMPT", time=0.25)
    rec.text("llm/attempt1/planner/1/code", code, time=0.3)
    rec.text("planner/say", "picking the red block", time=0.4)
    rec.text("llm/attempt1/planner/1/error", "PlanError: line 3: NameError: name 'put_first_on_second' is not defined",
             time=0.5)
    rec.text("llm/attempt1/api_calls", "get_obj_pos('red block') -> [0.5, 0.1, 0.02]", time=0.5)
    rec.text("llm/attempt1/verdict", "not achieved (error: ...)", time=0.6)
    rec.text("llm/attempt1/report", "REPORTER-REASONING", time=0.6)
    rec.text("llm/attempt1/parse_completion/1/result", "judge = False\nreason = 'JUDGE-REASON'", time=0.6)
    rec.text("planner/say", "trying again", time=1.0)
    rec.text("llm/attempt2/planner/1/code", "pass\n", time=1.1)
    rec.text("reference/print", "OTHER-TEXT", time=1.2)
    rec.text("verdict", "FAILURE (progress 0.00)", time=2.0)
    rec.finish({"task": "t", "seed": 1, "agent": "llm", "success": False, "progress": 0.0, "primitives": 0,
                "error": "PlanError: line 3: NameError"})
    rec.close()

    log = read_episode(p)
    doc = log.attempts["1"]
    lines = doc.splitlines()
    marked = [ln for ln in lines if ln.startswith(">>")]
    assert marked == [">> 3 | put_first_on_second(a, b)"]
    assert "   2 | b = 2" in lines
    order = [doc.index(x) for x in ("## Plan", "**Error** — line 3: `put_first_on_second(a, b)`", "## Verdict",
                                    "REPORTER-REASONING", "JUDGE-REASON", "## API calls", "## Prompts and completions",
                                    "PROMPT-1", "COMPLETION-1", "HELPER-PROMPT")]
    assert order == sorted(order)
    assert "# Attempt 2" in log.attempts["2"] and "OTHER-TEXT" in log.attempts["other"]
    assert log.logs["planner/say"] == ["picking the red block", "trying again"]  # a text log, every line

    ent = _read(p)
    assert all(s for s, _ in ent["/text/verdict"]) and all(s for s, _ in ent["/text/goal"])  # static
    assert all(s for s, _ in ent["/attempts/1"])
    # the same views as the failed episode: one layout for every episode
    views = _views(p)
    assert views == _views(failed[0])
    assert {"world": "/world", "summary": "/summary", "attempt 1": "/attempts/1", "attempt 3": "/attempts/3",
            "say": "/text/planner/say", "primitives": "/text/primitives"}.items() <= views.items()


def test_replay_lists_failed_episodes_of_a_run(failed, tmp_path):
    from capmj.bench.results import EPISODES, ResultsWriter

    path, result, _ = failed
    run = tmp_path / "run"
    (run / "rrd").mkdir(parents=True)
    target = run / "rrd" / "failed.rrd"
    target.write_bytes(path.read_bytes())
    with ResultsWriter(run / EPISODES) as w:
        w.write({**result.to_dict(), "rrd": "rrd/failed.rrd"})
        w.write({**result.to_dict(), "seed": SEED + 1, "success": True, "rrd": None})
    proc = subprocess.run([sys.executable, "-m", "capmj.replay", str(run)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    assert out.startswith(f"1 failed episode(s) in {run} (of 2)")
    assert f"why:  {result.diagnostics[0]}" in out
    assert f"open: {sys.executable} -m capmj.replay {target} --open" in out
    bad = subprocess.run([sys.executable, "-m", "capmj.replay", str(tmp_path)], capture_output=True, text=True,
                         timeout=120)
    assert bad.returncode == 2 and "episodes.jsonl" in bad.stderr


def test_replay_prints_summary_and_open_without_display(failed, monkeypatch, capsys):
    from capmj.replay.cli import main
    from capmj.replay.viewer import viewer_command

    path, result, _ = failed
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main([str(path), "--open"]) == 0
    out = capsys.readouterr().out
    assert "verdict:     FAILURE" in out and f"  - {result.diagnostics[0]}" in out
    assert out.count("  #") == result.primitives
    assert "ssh -N -L 9090:localhost:9090" in out and f"{path} --web" in out
    cmd = viewer_command()  # the viewer of this Python environment, not whatever is on PATH
    assert cmd is not None and (cmd[0] == sys.executable or Path(cmd[0]).parent == Path(sys.executable).parent)


def test_replay_rejects_non_rrd(tmp_path):
    bad = tmp_path / "x.rrd"
    bad.write_text("not a rerun file")
    from capmj.replay.cli import main

    assert main([str(bad)]) == 2
    assert main([str(tmp_path / "missing.rrd")]) == 2


def test_recorder_without_world_keeps_time_monotonic(tmp_path):
    from capmj.log import RerunRecorder
    from capmj.replay import read_episode

    p = tmp_path / "r.rrd"
    rec = RerunRecorder(p, task="t", seed=1, agent="a")
    quat = (1.0, 0.0, 0.0, 0.0)
    for t in (0.0, 0.05, 0.10):
        rec.frame(t, {"obj1": ((0.5, 0.0, t), quat)})
    rec.text("llm/planner/stale", "a time in the past must not look like a reset", time=0.02)
    for t in (0.0, 0.05):  # a reset to the initial state (re-plan): raw time goes back
        rec.frame(t, {"obj1": ((0.6, 0.0, t), quat)})
    rec.primitive(1, 0.05, {"ok": False, "status": "no_grip", "obj_id": None, "pick": (0.5, 0, 0.02),
                            "place": (0.6, 0, 0.02), "final_pos": None, "attempt": 1})
    rec.finish({"task": "t", "seed": 1, "agent": "a", "success": False, "progress": 0.0, "primitives": 1})
    rec.close()
    log = read_episode(p)
    assert log.summary["primitive_log"][0]["status"] == "no_grip"
    times = _seconds(_read(p)["/world/objects/obj1"], "Transform3D:translation")
    # every other frame is kept, plus the first after the reset and the last before a primitive;
    # the reset continues the timeline one frame period (0.05 s) after the last frame
    assert times == pytest.approx([0.0, 0.10, 0.15, 0.20])


def test_camera_images_logged_and_exported_with_depth_preview(tmp_path):
    pytest.importorskip("capmj.sim.cameras")
    from PIL import Image

    from capmj.replay import export_frames, read_episode

    p = tmp_path / "img.rrd"
    res = record_episode(get_task(TASK), SEED, WrongBowlAgent(), p, images=True)
    log = read_episode(p)
    if log.summary.get("image_error"):
        pytest.skip(f"no rendering here: {log.summary['image_error']}")
    # initial images (primitive 0) + one set per primitive, for each of the 3 cameras, rgb + depth
    assert log.summary["images_logged"] == 2 * 3 * (res.primitives + 1)
    frames = export_frames(p, tmp_path / "frames")
    names = {f.name for f in frames}
    assert "front_rgb_p000.png" in names and f"front_depth_p{res.primitives:03d}.png" in names
    depth = Image.open(tmp_path / "frames" / "front_depth_p000.png")
    assert depth.mode.startswith("I") and 300 < depth.getextrema()[0] < 5000  # millimetres
    preview = np.asarray(Image.open(tmp_path / "frames" / "front_depth_p000_preview.png"))
    assert preview.dtype == np.uint8 and preview.shape[2] == 3
    assert preview.std() > 20 and len(np.unique(preview.reshape(-1, 3), axis=0)) > 50  # not black, a colour map
