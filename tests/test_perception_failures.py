"""Perception error as a result: recorded per episode, shown per task, and a miss it causes is
labelled ``perception`` — in real physics, with real renders, the perceiver's estimates shifted.

The biased perceivers below are the built-in one with its output moved; the images, the
tracker, the primitive and the audit against the truth are the real ones.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass, replace

import pytest

from capmj.agents.base import EpisodeContext
from capmj.agents.api.perceived import PerceivedAPI
from capmj.bench.failures import classify
from capmj.bench.migrate import as_record, load_record
from capmj.bench.report import markdown
from capmj.bench.results import summarize
from capmj.errors import MotionFailed, PerceptionFailed, describe
from capmj.perception import ClassicalPerceiver, Detection, RGBDBundle
from capmj.records import SCHEMA, EpisodeRecord, PerceptionCall, PerceptionNotes
from capmj.runner import run_episode
from capmj.tasks.protocol import make_scene
from capmj.tasks.registry import get_task

TASK, SEED = "stack-all-blocks-on-a-zone", 10005


def _shift(d: Detection, dx: float) -> Detection:
    lo, hi = d.aabb
    return replace(d, position=(d.position[0] + dx, *d.position[1:]),
                   aabb=((lo[0] + dx, *lo[1:]), (hi[0] + dx, *hi[1:])))  # type: ignore[arg-type]


@dataclass(frozen=True)
class _Shifted:
    """The built-in perceiver, with every block perceived ``dx`` metres off along x."""

    dx: float

    def perceive(self, bundle: RGBDBundle) -> tuple[Detection, ...]:
        return tuple(_shift(d, self.dx) if d.kind == "block" else d for d in ClassicalPerceiver().perceive(bundle))


class _PutFirstBlockOnZone:
    """An agent that puts the first perceived block on the zone, seeing through ``perceiver``."""

    name, model = "probe", None

    def __init__(self, perceiver) -> None:
        self.perceiver = perceiver

    def act(self, ctx: EpisodeContext) -> None:
        api = PerceivedAPI(ctx, self.perceiver, name="shifted")
        fns = api.functions()
        names = fns["get_obj_names"]()
        block = next(n for n in names if n.startswith("movable"))
        fns["put_first_on_second"](block, next(n for n in names if "zone" in n))


def test_a_pick_at_a_wrong_perceived_centre_fails_as_perception_and_is_recorded() -> None:
    r = run_episode(get_task(TASK), SEED, _PutFirstBlockOnZone(_Shifted(0.05)))
    assert r.error_type == "PerceptionFailed", r.error
    assert r.error.startswith("RuntimeError: put_first_on_second(")  # the text a plan sees is the motion failure's
    rec = as_record(r)
    assert rec.failure == "perception"
    notes = rec.perception
    assert notes is not None and notes.perceiver == "shifted" and notes.pick_misses == (1,)
    reset = notes.at_reset
    # 5 cm is beyond the 2 cm matching gate: each block is missed and its estimate a false detection
    blocks = sum(o.kind == "block" for o in make_scene(get_task(TASK), SEED).objects)
    assert reset is not None and reset.stage == "reset" and reset.missed == reset.false_detections == blocks
    assert reset.erred and notes.erred(1)
    # the same line read back from episodes.jsonl keeps all of it
    assert load_record(json.loads(json.dumps(rec.to_dict()))) == rec


def test_an_accurate_perceiver_records_small_errors_and_no_miss() -> None:
    r = run_episode(get_task(TASK), SEED, _PutFirstBlockOnZone(_Shifted(0.0)))
    assert r.error is None, r.error
    notes = r.perception
    assert notes is not None and notes.pick_misses == ()
    assert [c.stage for c in notes.calls] == ["reset", "move 1"]
    for c in notes.calls:
        assert (c.missed, c.false_detections, c.color_errors) == (0, 0, 0)
        assert c.max_pos_mm is not None and c.max_pos_mm < 5
    assert not notes.erred(1)


def test_a_failed_clean_run_after_a_wrong_view_is_perception_else_physics_or_wrong_plan() -> None:
    base = as_record(run_episode(get_task(TASK), SEED, _PutFirstBlockOnZone(_Shifted(0.0))))
    assert base.success is False and base.failure == "wrong_plan"  # one block of several: not the goal
    ok = PerceptionCall(1, "reset", 5, 5, 0, 0, median_pos_mm=0.5, max_pos_mm=1.0)
    after = PerceptionCall(1, "move 1", 5, 5, 0, 0, median_pos_mm=0.5, max_pos_mm=1.0)
    far = dataclasses.replace(ok, max_pos_mm=12.0)
    missed = dataclasses.replace(ok, missed=1)

    def label(*calls: PerceptionCall, misses: tuple[int, ...] = ()) -> str | None:
        return classify(replace(base, perception=PerceptionNotes("rgbd", calls, misses)))

    assert label(ok, after) == "wrong_plan"
    assert label(far, after) == "perception" and label(missed, after) == "perception"
    assert label(ok, dataclasses.replace(after, missed=1)) == "wrong_plan"  # the last view: nothing acted on it
    assert label(missed) == "perception"  # ... unless it was the only one
    assert label(ok, after, misses=(1,)) == "perception"
    assert label(dataclasses.replace(ok, attempt=2), after) == "wrong_plan"  # another attempt's view


def test_perception_failed_is_a_motion_failure_with_its_own_label() -> None:
    exc = PerceptionFailed("put_first_on_second('b') failed: no_grip: nothing under the cup", status="no_grip")
    assert isinstance(exc, MotionFailed) and describe(exc).startswith("RuntimeError: ")
    rec = as_record(run_episode(get_task(TASK), SEED, _PutFirstBlockOnZone(_Shifted(0.0))))
    failed = replace(rec, success=False, error=describe(exc), error_type="PerceptionFailed", error_status="no_grip")
    motion = replace(failed, error_type="MotionFailed")
    assert (classify(failed), classify(motion)) == ("perception", "motion")


def test_old_lines_without_perception_load_and_summaries_show_it_per_task() -> None:
    rec = as_record(run_episode(get_task(TASK), SEED, _PutFirstBlockOnZone(_Shifted(0.05))))
    line = rec.to_dict()
    assert line["schema"] == SCHEMA == "capmj.episode/3"
    v2 = {k: v for k, v in line.items() if k != "perception"} | {"schema": "capmj.episode/2"}
    old = load_record(v2)
    assert old.perception is None and old.failure == "perception"  # the stored label is kept
    state = replace(rec, perception=None)
    assert "perception" not in state.to_dict()  # state-mode lines are unchanged
    with pytest.raises(Exception, match="schema"):
        EpisodeRecord.from_dict(v2)
    summary = summarize([rec])
    p = summary["tasks"][TASK]["probe"]["perception"]
    assert (p["episodes"], p["erred"], p["pick_misses"]) == (1, 1, 1)
    assert p["reset"]["missed"] == p["reset"]["false"] > 0 and p["after_moves"]["views"] == 1
    md = markdown(summary)
    assert "## Perception (rgbd)" in md and "| perception |" in md.split("## Failures")[1].splitlines()[4]
    assert "perception" not in summarize([state])["overall"]["probe"]


def test_the_perception_mode_is_in_the_manifest_and_the_summary(tmp_path) -> None:
    from capmj.bench.cli import main

    out = tmp_path / "run"
    assert main(["--agent", "reference", "--perception", "rgbd", "--tasks", TASK, "--seeds", str(SEED),
                 "--workers", "0", "--no-log", "--no-progress", "--out", str(out)]) == 0
    config = json.loads((out / "config.json").read_text())
    assert config["manifest"]["perception"] == "rgbd" and config["args"]["agent_options"]["perception"] == "rgbd"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["configs"]["reference"]["perception"] == "rgbd"
    md = (out / "summary.md").read_text()
    assert "Perception: reference = rgbd" in md and "## Perception (rgbd)" in md
    (line,) = [json.loads(x) for x in (out / "episodes.jsonl").read_text().splitlines()]
    assert line["perception"]["perceiver"] == "rgbd" and line["perception"]["calls"][0]["stage"] == "reset"
