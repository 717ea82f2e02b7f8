"""Moved cameras: the perceiver localises objects through the extrinsics it is given, not through
constants — and a stale calibration makes perception error grow until an episode fails as
``perception``, recorded.

Cameras are really moved in the MuJoCo model (position and a turn about the vertical), so the
renders are those of the moved cameras; the rig reports their new extrinsics.
"""

from __future__ import annotations

import math
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from capmj.agents.api.perceived import PerceivedAPI
from capmj.agents.api.perception_audit import true_objects
from capmj.agents.reference import ReferenceAgent
from capmj.bench.migrate import as_record
from capmj.perception import ClassicalPerceiver, Detection, RGBDBundle
from capmj.perception.score import score
from capmj.runner import run_episode
from capmj.sim.cameras import CameraRig
from capmj.sim.world import World
from capmj.tasks.protocol import make_scene
from capmj.tasks.registry import get_task

MOVES = {"front": ((-0.05, 0.06, 0.04), 5.0), "left": ((0.05, -0.03, -0.05), -4.0), "right": ((0.04, 0.05, 0.03), 3.0)}
"""camera -> (shift in m, turn about world z in degrees)."""


def move_camera(world, name: str, shift, turn_deg: float) -> None:
    """Move and turn one scene camera of ``world`` (about world z, through the camera)."""
    m = world.model
    cid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_CAMERA, name)
    m.cam_pos[cid] += np.asarray(shift, float)
    half = math.radians(turn_deg) / 2
    turned = np.zeros(4)
    mujoco.mju_mulQuat(turned, np.array([math.cos(half), 0.0, 0.0, math.sin(half)]), m.cam_quat[cid].copy())
    m.cam_quat[cid] = turned
    # The table's world-body cameras are static, and with sleeping enabled MuJoCo does not
    # recompute static poses: recompute the camera poses once with sleeping off.
    flags = m.opt.enableflags
    m.opt.enableflags = flags & ~int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    mujoco.mj_camlight(m, world.data)
    m.opt.enableflags = flags


def _calibration(world) -> dict[str, np.ndarray]:
    with CameraRig(world) as rig:
        return {n: rig.extrinsics(n) for n in rig.camera_names}


class StaleCalibration:
    """The built-in perceiver, handed the extrinsics of an old calibration instead of the rig's."""

    def __init__(self, calibration: dict[str, np.ndarray]) -> None:
        self.calibration = calibration

    def perceive(self, bundle: RGBDBundle) -> tuple[Detection, ...]:
        views = tuple(replace(v, extrinsics=self.calibration[v.name]) for v in bundle.views)
        return ClassicalPerceiver().perceive(RGBDBundle(views))


def test_moved_cameras_still_localise_every_object_through_their_extrinsics() -> None:
    world = World(make_scene(get_task("stack-blocks-by-color-and-size"), 10005).objects)
    world.settle()
    before = _calibration(world)
    for name, (shift, turn) in MOVES.items():
        move_camera(world, name, shift, turn)
    with CameraRig(world) as rig:
        bundle = RGBDBundle.from_frames(rig.render_all(seg=False, heightmap=False).views.values())
    for v in bundle.views:
        assert np.linalg.norm(v.extrinsics[:3, 3] - before[v.name][:3, 3]) > 0.05  # really moved
    _, truth = true_objects(world)
    s = score(ClassicalPerceiver().perceive(bundle), truth)
    assert s.recall == s.precision == 1.0, s.to_dict()
    assert all(m.kind_ok and m.color_ok and m.size_ok for m in s.matches), s.to_dict()
    assert max(m.position_error for m in s.matches) < 0.005, s.to_dict()
    # The same pictures with the old extrinsics put the objects elsewhere: the estimate follows
    # the calibration it is given.
    stale = score(StaleCalibration(before).perceive(bundle), truth)
    worst = max((m.position_error for m in stale.matches), default=math.inf)
    assert stale.recall < 1.0 or worst > 0.01, stale.to_dict()


@pytest.mark.parametrize("calibrated", [True, False])
def test_a_bumped_camera_rig_fails_the_episode_as_perception_unless_recalibrated(
        calibrated: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    """The rig is shifted 5 cm before the plan runs.  Recalibrated (the perceiver gets the rig's
    extrinsics), the reference plan succeeds; with the old calibration its picks miss, the
    episode fails as ``perception`` and its record shows the error."""
    import capmj.agents.reference as reference

    def bumped_api(ctx, perception: str) -> PerceivedAPI:
        old = _calibration(ctx.world)
        for name in old:
            move_camera(ctx.world, name, (0.0, 0.05, 0.0), 0.0)
        perceiver = ClassicalPerceiver() if calibrated else StaleCalibration(old)
        return PerceivedAPI(ctx, perceiver, name="bumped")

    monkeypatch.setattr(reference, "make_api", bumped_api)
    rec = as_record(run_episode(get_task("put-block-into-matching-bowl"), 10003, ReferenceAgent(perception="rgbd")))
    notes = rec.perception
    assert notes is not None and notes.perceiver == "bumped"
    reset = notes.at_reset
    assert reset is not None
    if calibrated:
        assert rec.success and rec.failure is None, (rec.error, rec.diagnostics)
        assert (reset.missed, reset.false_detections, notes.pick_misses) == (0, 0, ())
        assert reset.max_pos_mm is not None and reset.max_pos_mm < 5
    else:
        assert not rec.success and rec.failure == "perception"
        assert rec.error_type == "PerceptionFailed" and "no_grip" in (rec.error or "")
        assert reset.missed == reset.objects and reset.false_detections == reset.detections  # all 5 cm off
        assert notes.pick_misses == (1,) and notes.erred(1)
