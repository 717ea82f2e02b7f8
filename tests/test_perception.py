"""The perception layer: isolation from the simulator, footprint geometry, detections vs the truth.

Only these tests (and ``benchmarks/perception.py``) read the ground truth; the perceiver never
does.  The isolation tests run the perceiver on images saved to disk in a fresh interpreter that
imports no world and no MuJoCo, so a leak of simulator state into ``capmj.perception`` fails here.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from capmj.perception import ClassicalPerceiver, RGBDBundle
from capmj.perception.footprint import fit_l, min_area_rect, square_yaw

SRC = Path(__file__).resolve().parents[1] / "src"


def _render(objects) -> tuple[RGBDBundle, list]:
    """The three views of a settled world and its true objects (poses read after settling)."""
    from capmj.sim.cameras import CameraRig
    from capmj.sim.world import World

    world = World(objects)
    world.settle()
    with CameraRig(world) as rig:
        views = rig.render_all(seg=True, heightmap=False).views.values()
        bundle = RGBDBundle.from_frames(views)
    truth = [(o, world.pose(o.obj_id)) for o in objects]
    return bundle, truth


def _spawn(task: str, seed: int):
    from capmj.tasks.protocol import make_scene
    from capmj.tasks.registry import get_task

    return make_scene(get_task(task), seed).objects


def _subprocess_env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(SRC), env.get("PYTHONPATH", "")])
    return env


# ---------------------------------------------------------------------- isolation
def test_package_imports_no_simulator() -> None:
    code = ("import sys, pkgutil, importlib, capmj.perception as p\n"
            "for m in pkgutil.iter_modules(p.__path__): importlib.import_module('capmj.perception.' + m.name)\n"
            "bad = sorted(m for m in sys.modules if m.split('.')[0] == 'mujoco' or m in "
            "('capmj.sim.world', 'capmj.sim.cameras', 'capmj.sim.scene', 'capmj.tasks', 'capmj.agents', "
            # object state and the footprint model (which reads specs and poses): the fixture's walls
            # come from capmj.sim.shapes, constants only
            "'capmj.sim.state', 'capmj.sim.footprint', 'capmj.sim.pose'))\n"
            "print(bad)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_subprocess_env(),
                         check=True, timeout=120)
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


def test_bundle_carries_no_segmentation_and_round_trips(tmp_path: Path) -> None:
    bundle, _ = _render(_spawn("put-block-into-matching-bowl", 10001))
    for view in bundle.views:
        assert set(vars(view)) == {"name", "rgb", "depth", "intrinsics", "extrinsics"}
    back = RGBDBundle.load(bundle.save(tmp_path / "scene.npz"))
    assert [v.name for v in back.views] == [v.name for v in bundle.views] == ["front", "left", "right"]
    for a, b in zip(bundle.views, back.views):
        assert np.array_equal(a.rgb, b.rgb) and np.array_equal(a.depth, b.depth)
        assert np.array_equal(a.intrinsics, b.intrinsics) and np.array_equal(a.extrinsics, b.extrinsics)


def test_perceiver_on_saved_images_in_a_process_without_a_world(tmp_path: Path) -> None:
    """Images on disk -> a fresh interpreter with no world -> the same detections as in-process,
    and every true object found there with its kind and colour."""
    bundle, truth = _render(_spawn("stack-blocks-of-same-color", 10003))
    path = bundle.save(tmp_path / "scene.npz")
    code = ("import json, sys\n"
            "from capmj.perception import ClassicalPerceiver, RGBDBundle\n"
            f"dets = ClassicalPerceiver().perceive(RGBDBundle.load({str(path)!r}))\n"
            "assert 'mujoco' not in sys.modules and 'capmj.sim.world' not in sys.modules\n"
            "print(json.dumps([[d.kind, d.color, d.size, list(d.position)] for d in dets]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_subprocess_env(),
                         check=True, timeout=300)
    remote = json.loads(out.stdout)
    local = [[d.kind, d.color, d.size, list(d.position)] for d in ClassicalPerceiver().perceive(bundle)]
    assert remote == local  # deterministic across processes
    assert len(remote) == len(truth)
    for spec, pose in truth:
        near = min(remote, key=lambda d: math.dist(d[3][:2], pose.pos[:2]))
        assert (near[0], near[1], near[2]) == (spec.kind, spec.color, spec.size), spec.name
        assert math.dist(near[3][:2], pose.pos[:2]) < 0.01, spec.name


# ---------------------------------------------------------------------- footprint geometry
def _rect_points(cx: float, cy: float, length: float, width: float, angle: float, step: float) -> np.ndarray:
    u, v = np.meshgrid(np.arange(-length / 2, length / 2 + 1e-9, step), np.arange(-width / 2, width / 2 + 1e-9, step))
    c, s = math.cos(angle), math.sin(angle)
    return np.stack([cx + c * u.ravel() - s * v.ravel(), cy + s * u.ravel() + c * v.ravel()], axis=1)


@pytest.mark.parametrize("angle", [0.0, 0.3, -1.2, 1.5])
def test_min_area_rect_recovers_a_rotated_rectangle(angle: float) -> None:
    r = min_area_rect(_rect_points(0.4, -0.1, 0.1, 0.04, angle, 0.002))
    assert (r.cx, r.cy) == pytest.approx((0.4, -0.1), abs=1e-6)
    assert (r.length, r.width) == pytest.approx((0.1, 0.04), abs=1e-6)
    assert math.remainder(r.angle - angle, math.pi) == pytest.approx(0.0, abs=1e-6)
    square = min_area_rect(_rect_points(0.0, 0.0, 0.04, 0.04, angle, 0.002))
    assert math.remainder(square_yaw(square) - angle, math.pi / 2) == pytest.approx(0.0, abs=1e-6)


def _file_walls() -> list:
    """((centre x, y), half x, half y) of the walls as ``mjcf/fixture.xml`` has them (geoms g0, g1)."""
    import mujoco

    from capmj.resources import packaged

    m = mujoco.MjModel.from_xml_path(str(packaged("mjcf") / "fixture.xml"))
    walls = [m.geom(name) for name in ("g0", "g1")]
    return [((float(g.pos[0]), float(g.pos[1])), float(g.size[0]), float(g.size[1])) for g in walls]


def test_fixture_geometry_of_the_perceiver_is_that_of_the_file() -> None:
    """The perceiver reads the one definition of the walls (capmj.sim.shapes, shared with the
    footprint model): they are the file's, and the L's enclosing rectangle and the corner-to-origin
    offset the fit uses are those of those walls."""
    from capmj.sim.shapes import FIXTURE_ORIGIN_IN, FIXTURE_RECT, FIXTURE_WALLS

    walls = [((w.centre[0], w.centre[1]), w.half[0], w.half[1]) for w in FIXTURE_WALLS]
    for (c, hx, hy), (fc, fhx, fhy) in zip(walls, _file_walls(), strict=True):
        assert c == pytest.approx(fc, abs=1e-9) and (hx, hy) == pytest.approx((fhx, fhy), abs=1e-9)
    lo = np.min([np.subtract(c, (hx, hy)) for c, hx, hy in walls], axis=0)  # the L's outer corner
    hi = np.max([np.add(c, (hx, hy)) for c, hx, hy in walls], axis=0)
    assert tuple(hi - lo) == pytest.approx(FIXTURE_RECT, abs=1e-12)
    assert tuple(-lo) == pytest.approx((FIXTURE_ORIGIN_IN, FIXTURE_ORIGIN_IN), abs=1e-12)


@pytest.mark.parametrize("yaw", [0.0, 0.8, 2.5, -2.0])
def test_fit_l_finds_the_fixture_origin_and_yaw(yaw: float) -> None:
    # The walls of mjcf/fixture.xml in the fixture's frame, then turned by yaw about the origin (0.5, 0.1).
    local = np.concatenate([_rect_points(x, y, 2 * hx, 2 * hy, 0.0, 0.002) for (x, y), hx, hy in _file_walls()])
    c, s = math.cos(yaw), math.sin(yaw)
    xy = local @ np.array([[c, s], [-s, c]]) + (0.5, 0.1)
    fit = fit_l(xy, 0.002)
    assert (fit.x, fit.y) == pytest.approx((0.5, 0.1), abs=1e-3)
    assert math.remainder(fit.yaw - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-3)
    assert fit.mismatch < 0.05


# ---------------------------------------------------------------------- fast paths = plain formulations
def _plain_view_points(view):
    """The back-projection and normals written plainly, on (H, W, 3) arrays (the fast code's reference)."""
    from capmj.perception.cloud import _DEPTH_FAR, UPRIGHT_COS, Z_MAX
    from capmj.sim.bounds import WORKSPACE as ws

    k, pose = view.intrinsics, view.extrinsics
    h, w = view.shape
    rot = pose[:3, :3].astype(np.float32)
    a = ((np.arange(w) + 0.5 - k[0, 2]) / k[0, 0]).astype(np.float32)
    b = ((np.arange(h) + 0.5 - k[1, 2]) / k[1, 1]).astype(np.float32)
    rays = a[None, :, None] * rot[:, 0] + b[:, None, None] * rot[:, 1] + rot[:, 2]
    pts = view.depth[..., None] * rays + pose[:3, 3].astype(np.float32)
    x, y, z = pts[..., 0], pts[..., 1], pts[..., 2]
    keep = ((view.depth < _DEPTH_FAR) & (x >= ws.xmin) & (x < ws.xmax) & (y >= ws.ymin) & (y < ws.ymax)
            & (z > -0.01) & (z < Z_MAX))
    keep[-1, :] = keep[:, -1] = False
    kv, ku = np.nonzero(keep)
    p0 = pts[kv, ku]
    du, dv = pts[kv, ku + 1] - p0, pts[kv + 1, ku] - p0
    n = np.stack([du[:, 1] * dv[:, 2] - du[:, 2] * dv[:, 1], du[:, 2] * dv[:, 0] - du[:, 0] * dv[:, 2],
                  du[:, 0] * dv[:, 1] - du[:, 1] * dv[:, 0]], axis=1)
    n2 = n[:, 0] * n[:, 0] + n[:, 1] * n[:, 1] + n[:, 2] * n[:, 2]
    step2 = np.maximum((du * du).sum(axis=1), (dv * dv).sum(axis=1))
    up = (n[:, 2] * n[:, 2] > UPRIGHT_COS ** 2 * n2) & (n2 > 0) & (step2 < 0.006 ** 2)
    return p0.astype(np.float64), view.rgb[kv, ku], up


def test_fast_fusion_paths_give_the_bits_of_the_plain_ones() -> None:
    from capmj.perception.cloud import _view_points
    from capmj.perception.colour import _lab, _median_u8, srgb_to_lab

    bundle, _ = _render(_spawn("put-block-into-matching-bowl", 10001))
    for view in bundle.views:
        for fast, plain in zip(_view_points(view), _plain_view_points(view)):
            assert fast.dtype == plain.dtype and np.array_equal(fast, plain), view.name
    rng = np.random.default_rng(7)
    for n in (4097, 10000, 10001):
        px = rng.integers(0, 256, (n, 3)).astype(np.uint8)
        assert np.array_equal(_median_u8(px), np.median(px.astype(np.float64), axis=0))
        few = px[rng.integers(0, 300, n)]  # many pixels, few distinct colours, as in a render
        assert np.array_equal(srgb_to_lab(few), _lab(few)) and np.array_equal(srgb_to_lab(px), _lab(px))


# ---------------------------------------------------------------------- accuracy against the truth
def _truths(truth) -> list:
    from capmj.perception.score import TrueObject

    return [TrueObject(o.kind, o.color, o.size, pose.pos, pose.yaw) for o, pose in truth]


@pytest.mark.parametrize("task,seed", [("stack-blocks-by-color-and-size", 10005),
                                       ("put-block-into-mismatching-bowl", 10007),
                                       ("construct-circle-ball-middle", 10009)])
def test_spawn_scene_detected_exactly(task: str, seed: int) -> None:
    from capmj.perception.score import score

    bundle, truth = _render(_spawn(task, seed))
    s = score(ClassicalPerceiver().perceive(bundle), _truths(truth))
    assert (s.recall, s.precision) == (1.0, 1.0), s.to_dict()
    assert all(m.kind_ok and m.color_ok and m.size_ok for m in s.matches), s.to_dict()
    assert max(m.position_error for m in s.matches) < 0.005, s.to_dict()
    assert max(m.yaw_error or 0.0 for m in s.matches) < math.radians(8), s.to_dict()


def test_block_on_a_zone_of_its_own_colour_is_its_own_object() -> None:
    from capmj.perception.score import score
    from capmj.sim.objects import ObjectSpec

    objects = [ObjectSpec(1, "zone", "red", (0.5, 0.1, 0.0005), 0.4),
               ObjectSpec(2, "block", "red", (0.52, 0.09, 0.02), 0.1, "small"),
               ObjectSpec(3, "zone", "gray", (0.45, -0.2, 0.0005), -0.2, scale=1.5),
               ObjectSpec(4, "block", "silver", (0.45, -0.2, 0.01), 0.7, "tiny")]
    bundle, truth = _render(objects)
    dets = ClassicalPerceiver().perceive(bundle)
    s = score(dets, _truths(truth))
    assert (s.recall, s.precision) == (1.0, 1.0), s.to_dict()
    assert all(m.kind_ok and m.color_ok and m.size_ok for m in s.matches), s.to_dict()
    gray = next(d for d in dets if d.kind == "zone" and d.color == "gray")
    assert gray.scale == pytest.approx(1.5, abs=0.05)


def test_score_gates_and_counts_confusions() -> None:
    from capmj.perception.detect import Detection
    from capmj.perception.score import TrueObject, score

    box = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    truths = [TrueObject("block", "red", "small", (0.5, 0.0, 0.02), 0.1),
              TrueObject("block", "blue", "small", (0.4, 0.0, 0.02), 0.0)]
    dets = [Detection("block", "pink", "small", 1.0, (0.505, 0.0, 0.02), 0.1 + math.pi / 2, box, 0.9),
            Detection("block", "blue", "big", 1.0, (0.4, 0.05, 0.02), 0.0, box, 0.9)]  # 5 cm off: no match
    s = score(dets, truths)
    assert (s.recall, s.precision) == (0.5, 0.5)
    assert s.confusions == (("red", "pink"),)
    assert s.matches[0].yaw_error == pytest.approx(0.0, abs=1e-9)  # a square repeats every 90 degrees


def test_score_pairs_a_block_in_a_fixture_slot_with_itself_not_crosswise() -> None:
    # A fixture reports its slot (0, 0, 0), so a block inserted there stands at the fixture's own
    # position: both detections lie nearer the other kind's truth (1 mm) than their own (5 mm).
    from capmj.perception.detect import Detection
    from capmj.perception.score import TrueObject, score

    box = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    truths = [TrueObject("fixture", "brown", None, (0.500, 0.1, 0.02), 0.3),
              TrueObject("block", "red", "small", (0.506, 0.1, 0.02), 0.3)]
    dets = [Detection("block", "red", "small", 1.0, (0.501, 0.1, 0.02), 0.3, box, 0.9),
            Detection("fixture", "brown", None, 1.0, (0.505, 0.1, 0.02), 0.35, box, 0.9)]
    s = score(dets, truths)
    assert sorted((m.truth, m.detection) for m in s.matches) == [(0, 1), (1, 0)]
    assert all(m.kind_ok and m.color_ok and m.size_ok for m in s.matches) and s.confusions == ()
    assert [m.position_error for m in s.matches] == pytest.approx([0.005, 0.005], abs=1e-9)
    fixture = next(m for m in s.matches if m.truth == 0)
    assert fixture.yaw_error == pytest.approx(0.05, abs=1e-9)


def test_score_prefers_more_matches_to_matching_kinds() -> None:
    # A zone seen as a block still counts as matched (a kind error), rather than leaving the block
    # detection that could be its own kind's pair unmatched.
    from capmj.perception.detect import Detection
    from capmj.perception.score import TrueObject, score

    box = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    truths = [TrueObject("block", "red", "small", (0.5, 0.0, 0.02), 0.0),
              TrueObject("zone", "red", None, (0.53, 0.0, 0.02), 0.0)]
    dets = [Detection("block", "red", "small", 1.0, (0.512, 0.0, 0.02), 0.0, box, 0.9),
            Detection("block", "red", "small", 1.0, (0.495, 0.0, 0.02), 0.0, box, 0.9)]
    s = score(dets, truths)
    assert sorted((m.truth, m.detection) for m in s.matches) == [(0, 1), (1, 0)]
    assert s.to_dict()["kind_errors"] == 1


# ---------------------------------------------------------------------- names and tracking
def _block(color: str, x: float, y: float, z: float, size: str = "small"):
    from capmj.perception.detect import Detection
    from capmj.sim.objects import BLOCK_SIZES

    h = BLOCK_SIZES[size] / 2
    return Detection("block", color, size, 1.0, (x, y, z), 0.0, ((x - h, y - h, z - h), (x + h, y + h, z + h)), 0.9)


def test_object_names_are_todays_format() -> None:
    from capmj.perception.track import object_name
    from capmj.tasks.builtin import BENCHMARK_TASKS, GENERATED_TASKS

    for task in BENCHMARK_TASKS + GENERATED_TASKS:
        for o in _spawn(task, 10001):
            assert object_name(o.kind, o.color, o.size, o.obj_id) == o.name


def test_a_tower_of_five_keeps_all_five_names() -> None:
    from capmj.perception.track import Tracker

    colours = ["red", "blue", "green", "yellow", "pink"]
    table = [_block(c, 0.3 + 0.08 * k, 0.2, 0.02) for k, c in enumerate(colours)]
    tracker = Tracker.start(table)
    names = tracker.names
    assert [t.obj_id for t in tracker.objects] == [1, 2, 3, 4, 5]
    base = (0.5, -0.2)
    ids = {t.detection.color: t.obj_id for t in tracker.objects}
    for level, colour in enumerate(colours):
        # The robot puts `colour` on the tower; the cameras see the tower's top and the table.
        top = (base[0], base[1], 0.02 + 0.04 * level)
        seen = [_block(colour, *top)] + [d for d in table[level + 1:]]
        tracker = tracker.update(seen, moved={ids[colour]: top})
        assert tracker.names == names  # every block keeps its name, hidden ones included
    hidden = [t.detection.color for t in tracker.objects if not t.visible]
    assert sorted(hidden) == sorted(colours[:-1])
    # Taking the top block away (to the table) leaves the rest of the tower remembered.
    tracker = tracker.update([_block("yellow", base[0], base[1], 0.14), _block("pink", 0.7, 0.3, 0.02)],
                             moved={ids["pink"]: (0.7, 0.3, 0.02)})
    assert tracker.names == names
    assert {t.detection.color for t in tracker.objects if t.visible} == {"yellow", "pink"}


def test_a_fixed_object_cut_into_pieces_keeps_its_id_and_absorbs_them() -> None:
    from capmj.perception.detect import Detection
    from capmj.perception.track import Tracker

    def zone(x: float, y: float, half: float) -> Detection:
        return Detection("zone", "green", None, 1.0, (x, y, 0.0005), 0.0,
                         ((x - half, y - half, 0.0), (x + half, y + half, 0.001)), 0.9)

    whole = zone(0.5, 0.0, 0.06)
    tracker = Tracker.start([whole, _block("green", 0.3, 0.2, 0.02), _block("red", 0.3, -0.2, 0.02)])
    names = tracker.names
    # A block across the zone cuts its face into two halves, both too far off to match the zone;
    # a green block put inside the zone's box is matched by the move and stays a block; a red
    # piece inside it is not the zone's.
    halves = [zone(0.46, 0.0, 0.035), zone(0.545, 0.0, 0.02)]
    seen = [*halves, _block("green", 0.5, 0.0, 0.0205), _block("red", 0.3, -0.2, 0.02), _block("red", 0.52, 0.04, 0.02)]
    tracker = tracker.update(seen, moved={2: (0.5, 0.0, 0.0205)})
    assert tracker.names == names + ["movable small red block with obj_id 4"]
    assert tracker.by_id(1).detection == whole  # fixed: it stays where it was seen whole
    # Without the zone's pieces in view nothing says it is still there: it is dropped.
    assert 1 not in {t.obj_id for t in tracker.update([_block("red", 0.3, -0.2, 0.02)]).objects}


def test_a_block_that_vanishes_is_dropped_and_new_ones_get_fresh_ids() -> None:
    from capmj.perception.track import Tracker

    tracker = Tracker.start([_block("red", 0.4, 0.0, 0.02), _block("blue", 0.6, 0.0, 0.02)])
    tracker = tracker.update([_block("red", 0.401, 0.0, 0.02), _block("gold", 0.5, 0.3, 0.01, "tiny")])
    assert tracker.names == ["movable small red block with obj_id 1", "movable tiny gold block with obj_id 3"]
