"""Real headless rendering: depth, heightmap, segmentation, calibration, colours, helpers.

One rig per world is built once per module (GL context + MjrContext cost ~0.5 s).
"""

from __future__ import annotations

import io
import os
import subprocess
import sys
import time

import numpy as np
import pytest
from PIL import Image

from capmj.errors import ConfigError, RenderBackendError
from capmj.sim import gl
from capmj.sim.cameras import CameraRig, depth_to_visible, seg_to_visible, to_png
from capmj.sim.objects import ObjectSpec
from capmj.sim.world import World

RED, BLUE, ZONE = 1, 2, 3
SPECS = [
    ObjectSpec(RED, "block", "red", (0.5, 0.0, 0.02), 0.0, "small"),
    ObjectSpec(BLUE, "block", "blue", (0.4, 0.2, 0.03), 0.3, "big"),
    ObjectSpec(ZONE, "zone", "green", (0.6, -0.2, 0.0005)),
]


@pytest.fixture(scope="module")
def world() -> World:
    return World(SPECS)


@pytest.fixture(scope="module")
def rig(world: World):
    r = CameraRig(world)
    yield r
    r.close()


@pytest.fixture(scope="module")
def frames(rig: CameraRig):
    return {name: rig.render(name) for name in ("front", "left", "right")}


@pytest.fixture(scope="module")
def bare_front():
    with CameraRig(World([])) as r:
        yield r.render("front")


def _lookat_opencv(pos, target) -> np.ndarray:
    """Camera-to-world rotation (OpenCV axes) computed independently from the scene constants."""
    f = np.subtract(target, pos, dtype=float)
    f /= np.linalg.norm(f)
    right = np.cross(f, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(f, right)
    return np.column_stack([right, down, f])


def test_bare_table_depth_matches_geometry(bare_front) -> None:
    pos, target = np.array((1.0, 0.0, 0.75)), np.array((0.5, 0.0, 0.0))  # mjcf/table.xml "front"
    expected = np.linalg.norm(target - pos)  # the optical axis hits the table at the look-at point
    # The optical axis passes through the corner shared by the 4 central pixels.
    centre = bare_front.depth[239:241, 319:321].mean()
    assert abs(centre - expected) < 0.002, (centre, expected)
    assert bare_front.intrinsics[0, 0] == pytest.approx(450.0)
    assert tuple(bare_front.intrinsics[:2, 2]) == (320.0, 240.0)

    # Every pixel of the lower half sees the bare table: check the pinhole model pixel by pixel.
    rot = _lookat_opencv(pos, target)
    v, u = np.mgrid[250:480:23, 0:640:37]
    rays = np.stack([(u + 0.5 - 320) / 450, (v + 0.5 - 240) / 450, np.ones_like(u, float)], -1) @ rot.T
    z_depth = -pos[2] / rays[..., 2]  # camera-frame z of the ray point on the plane z = 0
    got = bare_front.depth[v, u]
    assert np.max(np.abs(got - z_depth)) < 0.002
    assert np.allclose(bare_front.extrinsics[:3, :3], rot, atol=1e-6)
    assert np.allclose(bare_front.extrinsics[:3, 3], pos, atol=1e-9)


def test_heightmap_reads_block_heights(rig: CameraRig) -> None:
    hm = rig.heightmap()
    assert hm.height.shape == (320, 160) and hm.height.dtype == np.float32
    assert hm.colormap.shape == (320, 160, 3) and hm.colormap.dtype == np.uint8
    assert hm.pixel_size == pytest.approx(0.003125)
    assert np.allclose(hm.bounds[:2], [[0.25, 0.75], [-0.5, 0.5]])
    red, blue = hm.pixel_of(0.5, 0.0), hm.pixel_of(0.4, 0.2)
    assert red == (160, 80) and blue == (224, 48)
    assert hm.height[red] == pytest.approx(0.04, abs=0.002)
    assert hm.height[blue] == pytest.approx(0.06, abs=0.002)
    assert hm.seg[red] == RED and hm.seg[blue] == BLUE
    zone = hm.pixel_of(0.6, -0.2)
    assert hm.seg[zone] == ZONE and hm.height[zone] == pytest.approx(0.001, abs=0.0005)
    for x, y in ((0.7, -0.45), (0.3, -0.3), (0.72, 0.4)):  # bare table
        assert abs(hm.height[hm.pixel_of(x, y)]) < 0.001
        assert hm.seg[hm.pixel_of(x, y)] == 0
    # A whole block footprint reads its height (rows = y, cols = x; 4 cm = 12.8 cells).
    r, c = red
    assert np.allclose(hm.height[r - 5:r + 6, c - 5:c + 6], 0.04, atol=0.002)
    assert np.all(hm.height >= 0)


def test_heightmap_robot_toggle(rig: CameraRig, world: World) -> None:
    tip, _ = world.tip_pose()
    cell = rig.heightmap().pixel_of(tip[0], tip[1])
    with_robot = rig.heightmap(include_robot=True)
    without = rig.heightmap(include_robot=False)
    # Seen from above, the tool axis is covered by the wrist: the arm reads at least the tip height.
    assert with_robot.height[cell] >= tip[2] - 0.005 and with_robot.seg[cell] == 0
    assert without.height[cell] < 0.001
    assert without.height[with_robot.pixel_of(0.4, 0.2)] == pytest.approx(0.06, abs=0.002)


@pytest.mark.parametrize("camera", ["front", "left", "right"])
def test_segmentation_and_backprojection(frames, world: World, camera: str) -> None:
    f = frames[camera]
    assert f.rgb.shape == (480, 640, 3) and f.depth.shape == (480, 640) and f.seg.dtype == np.int32
    ids, counts = np.unique(f.seg, return_counts=True)
    seen = dict(zip(ids.tolist(), counts.tolist()))
    for obj in (RED, BLUE, ZONE):
        assert seen.get(obj, 0) > 30, (camera, seen)
    assert set(seen) <= {0, RED, BLUE, ZONE}
    for obj in (RED, BLUE):
        spec = world.objects_by_id[obj]
        centre = np.array(world.pose(obj).pos)
        rows, cols = np.nonzero(f.seg == obj)
        # The seg centroid pixel, back-projected with its depth, lands on the block (~1 cm).
        v, u = int(round(rows.mean())), int(round(cols.mean()))
        assert f.seg[v, u] == obj
        p = f.unproject(v, u)[0]
        assert np.linalg.norm(p[:2] - centre[:2]) < 0.01 + spec.half_extents[0], (camera, p, centre)
        # All block pixels back-project onto the block's box; the top face is centred on it.
        pts = f.unproject(rows, cols)
        lo, hi = world.aabb(obj)
        assert np.all(pts >= lo - 0.004) and np.all(pts <= hi + 0.004), camera
        top = pts[pts[:, 2] > hi[2] - 0.002]
        assert len(top) > 20
        assert np.linalg.norm(top[:, :2].mean(0) - centre[:2]) < 0.004, (camera, top.mean(0), centre)
        # And the true centre projects into the block's segment.
        uc, vc = f.project(centre)[0]
        assert f.seg[int(vc), int(uc)] == obj


def test_rgb_colours(frames) -> None:
    for f in frames.values():
        red = f.rgb[f.seg == RED].astype(float).mean(0)
        blue = f.rgb[f.seg == BLUE].astype(float).mean(0)
        assert red[0] > 1.5 * red[1] and red[0] > 1.5 * red[2], (f.name, red)
        assert blue[2] > 1.3 * blue[0] and blue[2] > 1.1 * blue[1], (f.name, blue)


def test_unknown_camera(rig: CameraRig) -> None:
    with pytest.raises(ConfigError, match="front, left, right"):
        rig.render("ceiling")
    with pytest.raises(ConfigError):
        rig.render("top")  # orthographic: use heightmap()


def test_frames_are_read_only(frames) -> None:
    with pytest.raises(ValueError):
        frames["front"].depth[0, 0] = 1.0


def test_visualisation_helpers(frames, rig: CameraRig) -> None:
    vis = depth_to_visible(frames["left"].depth)
    assert vis.shape == (480, 640, 3) and vis.dtype == np.uint8
    assert vis.mean() > 60 and np.mean(vis.max(-1) < 20) < 0.01  # visibly non-black
    # nearer = brighter: the front camera's bottom rows are closer than its top rows
    fv = depth_to_visible(frames["front"].depth).astype(int).sum(-1)
    assert fv[470].mean() > fv[100].mean() + 150
    png = to_png(vis)
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert np.array_equal(np.asarray(Image.open(io.BytesIO(png))), vis)
    hm = rig.heightmap()
    assert to_png(depth_to_visible(hm.height, near=0.08, far=0.0))[:4] == b"\x89PNG"
    seg = seg_to_visible(frames["front"].seg)
    assert (seg[frames["front"].seg == 0] == 0).all() and seg[frames["front"].seg == RED].min() > 0
    with pytest.raises(ConfigError):
        to_png(frames["front"].depth)


def test_the_backend_is_chosen_when_rendering_starts_not_at_import() -> None:
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY")}
    code = ("import os, capmj.sim, capmj.sim.cameras as c, capmj.sim.gl as gl\n"
            "from capmj.sim.world import World\n"
            "before = repr((os.environ.get('MUJOCO_GL'), gl.STATE.chosen, gl.STATE.probe_results))\n"
            "with c.CameraRig(World([]), width=32, height=24) as rig:\n"
            "    rig.render('front')\n"
            "print(before, gl.STATE.chosen)\n")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    before, chosen = out.stdout.rsplit(maxsplit=1)
    assert before == "(None, None, {})" and chosen in ("egl", "osmesa")


def test_no_backend_error_names_packages(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(gl.STATE, "chosen", None)
    monkeypatch.setattr(gl, "probe_backend", lambda b: (False, "simulated"))
    monkeypatch.delitem(sys.modules, "mujoco")
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    with pytest.raises(RenderBackendError) as err:
        gl.ensure_gl_backend()
    msg = str(err.value)
    assert "apt-get install -y libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6" in msg
    assert "MUJOCO_GL=egl" in msg and "MUJOCO_GL=osmesa" in msg


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")
def test_forked_child_fails_fast_instead_of_hanging(rig: CameraRig) -> None:
    rig.render("front")  # this process now owns a GL context
    pid = os.fork()
    if pid == 0:  # child: Mesa would deadlock on its first GL call; we must raise instead
        code = 3
        try:
            rig.render("front")
        except RenderBackendError as exc:
            code = 0 if "spawn" in str(exc) else 4
        except BaseException:
            code = 5
        os._exit(code)
    deadline = time.monotonic() + 30
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        if time.monotonic() > deadline:
            os.kill(pid, 9)
            os.waitpid(pid, 0)
            pytest.fail("forked child hung while rendering")
        time.sleep(0.02)
    assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0, status


def test_renders_even_if_mujoco_was_imported_first_without_mujoco_gl() -> None:
    """mujoco imported before capmj with MUJOCO_GL unset picks GLFW; headless EGL/OSMesa is loaded anyway."""
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY")}
    code = ("import mujoco\n"
            "assert mujoco.GLContext.__module__ == 'mujoco.glfw'\n"
            "from capmj.sim.world import World\n"
            "from capmj.sim.cameras import CameraRig\n"
            "with CameraRig(World([])) as rig:\n"
            "    print(float(rig.render('front').depth[240, 320]))\n")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert abs(float(out.stdout.split()[-1]) - 0.9014) < 0.003


@pytest.mark.parametrize("camera", ["front", "left", "right"])
def test_rgbd_pass_gives_the_same_colour_and_depth_without_segmentation(frames, rig: CameraRig, camera: str) -> None:
    """``seg=False`` draws one pass and reads colour and depth from it: the same images as the
    two-pass render (the depth of the shaded pass equals that of the flat segmentation pass)."""
    full, fast = frames[camera], rig.render(camera, seg=False)
    assert fast.seg is None
    np.testing.assert_array_equal(fast.rgb, full.rgb)
    np.testing.assert_allclose(fast.depth, full.depth, atol=1e-4)


def test_render_all_renders_only_what_is_asked(rig: CameraRig) -> None:
    obs = rig.render_all(seg=False, heightmap=False)
    assert obs.heightmap is None
    assert set(obs.views) == set(rig.camera_names)
    assert all(v.seg is None and v.depth.shape == (rig.height, rig.width) for v in obs.views.values())


def test_a_thread_that_rendered_and_lives_on_does_not_lock_the_others_out(world: World) -> None:
    """EGL binds a context to one thread at a time: a pool thread that rendered (an episode thread
    of --concurrency, a failed episode's thumbnail) and stays alive must leave it free."""
    from concurrent.futures import ThreadPoolExecutor

    def top() -> np.ndarray:
        with CameraRig(world) as r:
            return np.asarray(r.heightmap(include_robot=False).height)

    with ThreadPoolExecutor(1) as pool:
        in_thread = pool.submit(top).result()
        in_main = top()  # the pool's thread is still alive here
        again = pool.submit(top).result()
    assert np.array_equal(in_thread, in_main) and np.array_equal(in_main, again)
