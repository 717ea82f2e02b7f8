"""On-demand RGB-D + segmentation rendering of the scene cameras, and the top-down heightmap.

:class:`CameraRig` renders the three perspective cameras of the scene ("front", "left", "right",
640x480, fx = fy = 450) and builds a Ravens-style heightmap from the orthographic "top" camera.
Nothing renders until asked (the oracle never does); the OpenGL context is created at the first
render and shared by the whole process (see :mod:`capmj.sim.gl`).

Per view two passes are drawn with shadows, reflections and multisampling off: a flat
segmentation pass whose depth buffer gives the metric depth, and the shaded colour pass.  What a
render returns is :mod:`capmj.sim.camera_frames`; colouring it for display,
:mod:`capmj.sim.image_colour`.

Conventions
-----------
- Images are row-major, row 0 at the top, shape ``(H, W[, 3])``.
- ``depth`` is the metric distance along the camera's optical axis (z-depth, not ray length).
  Pixels that see nothing hold the far-plane distance (5 m in the scene).
- ``seg`` holds capmj object ids (``ObjectSpec.obj_id``); 0 = robot, table, floor, background.
- ``intrinsics`` is the pinhole matrix ``[[fx,0,cx],[0,fy,cy],[0,0,1]]`` with ``cx = W/2``,
  ``cy = H/2`` (Ravens values); in these continuous coordinates the centre of pixel
  ``(row v, column u)`` is at ``(u + 0.5, v + 0.5)``.
- ``extrinsics`` is the camera-to-world pose with OpenCV axes (x right, y down, z forward), so
  ``world = extrinsics @ [(u+0.5-cx)/fx*d, (v+0.5-cy)/fy*d, d, 1]``.
- Heightmap: 320 rows = y from -0.5 to 0.5 (row 0 at y = -0.5), 160 columns = x from 0.25 to 0.75,
  cell ``[r, c]`` covers ``x in [0.25 + c p, 0.25 + (c+1) p)``, ``y in [-0.5 + r p, ...)`` with
  ``p = 0.003125``; values are metres above the table, clipped at 0.
"""

from __future__ import annotations

import os
import re
import weakref
from types import MappingProxyType
from typing import Any

import mujoco
import numpy as np

from capmj.errors import ConfigError, SimError
from capmj.sim.bounds import WORKSPACE
from capmj.sim.camera_frames import CameraFrame, Heightmap, Observation, frozen
from capmj.sim.gl import RENDER_LOCK, current_context, release_current
from capmj.sim.gl import make_current as gl_make_current
from capmj.sim.gl import register_cleanup, shared_gl_context
from capmj.sim.image_colour import depth_to_visible, seg_to_visible, to_png
from capmj.sim.scene import HEIGHTMAP_CAMERA, HEIGHTMAP_PIXEL

# Re-exported: the records a rig returns, and the colouring helpers that tests/test_cameras.py and
# callers import from here.
__all__ = ["IMAGE_H", "IMAGE_W", "VIEW_CAMERAS", "CameraFrame", "CameraRig", "Heightmap", "Observation",
           "depth_to_visible", "seg_to_visible", "to_png"]

VIEW_CAMERAS: tuple[str, ...] = ("front", "left", "right")
"""The perspective cameras of ``mjcf/table.xml`` in Ravens order (tests/test_mjcf.py keeps them equal):
the one list of camera names; the recorder and the env default to it."""
IMAGE_W, IMAGE_H = 640, 480
"""Default image size of the view cameras (RealSense-D415-like, as in Ravens)."""

_GEOM = int(mujoco.mjtObj.mjOBJ_GEOM)
_OBJ_BODY = re.compile(r"^obj(\d+)$")


def _geom_object_ids(model: mujoco.MjModel) -> np.ndarray:
    """Object id of each geom from body names ``obj<N>`` (used when given a bare model)."""
    body_obj = np.zeros(model.nbody, dtype=np.int32)
    for b in range(model.nbody):
        match = _OBJ_BODY.match(model.body(b).name)
        if match:
            body_obj[b] = int(match.group(1))
    return body_obj[model.geom_bodyid]


_KEPT_AFTER_FORK: list = []


def _free_mjr(holder: dict) -> None:
    ctx = holder.pop("mjr", None)
    if ctx is None:
        return
    with RENDER_LOCK:
        if holder.get("pid") != os.getpid() or not gl_make_current():
            # A forked child must make no GL call (Mesa deadlocks), not even in MjrContext's destructor.
            _KEPT_AFTER_FORK.append(ctx)
            return
        try:
            ctx.free()
        finally:
            release_current()


class CameraRig:
    """Renders the scene cameras of one world (or model) on demand; reuse it for every frame.

    ``robot_meshes=False`` draws the arm as its collision capsules, for speed.

    ``CameraRig(world)`` takes anything with ``.model``, ``.data`` and ``.geom_obj`` (a
    :class:`~capmj.sim.world.World`); ``CameraRig(model, data=data)`` a bare MuJoCo model, whose
    object ids are then read from the ``obj<N>`` body names.  The rig reads the live ``data`` at
    each render.  Call :meth:`close` (or use it as a context manager) when done; leftovers are
    freed at interpreter exit.
    """

    def __init__(self, world_or_model: Any, *, data: mujoco.MjData | None = None,
                 width: int = IMAGE_W, height: int = IMAGE_H, robot_meshes: bool = True) -> None:
        if isinstance(world_or_model, mujoco.MjModel):
            self.model = world_or_model
            if data is None:
                data = mujoco.MjData(self.model)
                mujoco.mj_forward(self.model, data)
            self.data = data
            self._geom_obj = _geom_object_ids(self.model)
        else:
            self.model = world_or_model.model
            self.data = world_or_model.data if data is None else data
            self._geom_obj = np.asarray(world_or_model.geom_obj, dtype=np.int32)
        m = self.model
        if not (0 < width <= m.vis.global_.offwidth and 0 < height <= m.vis.global_.offheight):
            raise ConfigError(f"image size {width}x{height} must be within the model's offscreen buffer "
                              f"{m.vis.global_.offwidth}x{m.vis.global_.offheight}")
        self.width, self.height = int(width), int(height)
        self.camera_names: tuple[str, ...] = tuple(
            m.camera(i).name for i in range(m.ncam)
            if m.cam_projection[i] == mujoco.mjtProjection.mjPROJ_PERSPECTIVE and m.camera(i).name)
        self._cam_ids = {n: m.camera(n).id for n in self.camera_names}
        try:
            self._top_id = m.camera(HEIGHTMAP_CAMERA).id
        except KeyError:
            self._top_id = -1
        self.bounds = WORKSPACE.as_array()
        self.pixel_size = HEIGHTMAP_PIXEL
        self.hm_cols = int(round((self.bounds[0, 1] - self.bounds[0, 0]) / self.pixel_size))
        self.hm_rows = int(round((self.bounds[1, 1] - self.bounds[1, 0]) / self.pixel_size))
        robot = (self._geom_obj == 0) & (m.geom_bodyid != 0)
        self._robot_geom = robot
        self._near = float(m.vis.map.znear * m.stat.extent)
        self._far = float(m.vis.map.zfar * m.stat.extent)
        self._opt = mujoco.MjvOption()
        if not robot_meshes:
            # The arm's collision capsules (group 3) instead of its visual meshes (group 2):
            # measured 2.5x faster for the three views + heightmap on llvmpipe.
            self._opt.geomgroup[2] = 0
            self._opt.geomgroup[3] = 1
        self._cam = mujoco.MjvCamera()
        self._cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._scene: mujoco.MjvScene | None = None
        self._gpu: dict = {}
        self._finalizer: weakref.finalize | None = None
        self._closed = False
        self._intrinsics: dict[str, np.ndarray] = {}
        for name, cid in self._cam_ids.items():
            fy = 0.5 * self.height / np.tan(np.radians(m.cam_fovy[cid]) / 2)
            self._intrinsics[name] = frozen(np.array([[fy, 0.0, self.width / 2], [0.0, fy, self.height / 2],
                                                       [0.0, 0.0, 1.0]]))

    # ------------------------------------------------------------------ context
    def _context(self) -> mujoco.MjrContext:
        if self._closed:
            raise SimError("CameraRig is closed")
        shared_gl_context()  # makes the shared context current; RenderBackendError if impossible
        mjr = self._gpu.get("mjr")
        if mjr is None:
            mjr = mujoco.MjrContext(self.model, mujoco.mjtFontScale.mjFONTSCALE_50)
            mjr.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
            self._gpu["mjr"] = mjr
            self._gpu["pid"] = os.getpid()
            self._finalizer = register_cleanup(self, _free_mjr, self._gpu)
            self._scene = mujoco.MjvScene(self.model, maxgeom=max(1000, 4 * self.model.ngeom))
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, mjr)
        return mjr

    def close(self) -> None:
        """Free the GPU resources of this rig (the shared GL context stays for other rigs)."""
        if self._finalizer is not None and self._finalizer.alive:
            self._finalizer()  # makes the shared context current itself (no GL call after a fork)
        self._closed = True

    def __enter__(self) -> "CameraRig":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ drawing
    def _update(self, cam_id: int, hide_robot: bool = False) -> mujoco.MjvScene:
        scene = self._scene
        assert scene is not None
        self._cam.fixedcamid = cam_id
        mujoco.mjv_updateScene(self.model, self.data, self._opt, None, self._cam,
                               mujoco.mjtCatBit.mjCAT_ALL, scene)
        scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
        scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
        if hide_robot:
            for g in scene.geoms[: scene.ngeom]:
                if g.objtype == _GEOM and self._robot_geom[g.objid]:
                    g.pos[2] = -1.0e4  # parked beyond the far plane
        return scene

    def _draw(self, scene: mujoco.MjvScene, mjr: mujoco.MjrContext, w: int, h: int, seg: bool = True
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Raw (bottom-up) rgb uint8, depth-buffer float32 and object-id int32 images.

        Without ``seg`` one shaded pass gives colour and depth together; with it a flat
        segmentation pass (whose depth buffer is read) comes first.
        """
        rect = mujoco.MjrRect(0, 0, w, h)
        zbuf = np.empty((h, w), np.float32)
        rgb = np.empty((h, w, 3), np.uint8)
        if not seg:
            mujoco.mjr_render(rect, scene, mjr)
            mujoco.mjr_readPixels(rgb, zbuf, rect, mjr)
            return rgb, zbuf, None
        ids_rgb = np.empty((h, w, 3), np.uint8)
        scene.flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = 1
        scene.flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = 1
        mujoco.mjr_render(rect, scene, mjr)
        mujoco.mjr_readPixels(ids_rgb, zbuf, rect, mjr)
        scene.flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = 0
        scene.flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = 0
        mujoco.mjr_render(rect, scene, mjr)
        mujoco.mjr_readPixels(rgb, None, rect, mjr)
        # Segmentation colour = scene-geom segid + 1 (0 = nothing); map it to object ids.
        lut = np.zeros(scene.ngeom + 2, np.int32)
        for g in scene.geoms[: scene.ngeom]:
            if g.objtype == _GEOM and 0 <= g.segid <= scene.ngeom:
                lut[g.segid + 1] = self._geom_obj[g.objid]
        code = ids_rgb[..., 0].astype(np.int32) | (ids_rgb[..., 1].astype(np.int32) << 8) \
            | (ids_rgb[..., 2].astype(np.int32) << 16)
        return rgb, zbuf, lut[np.minimum(code, len(lut) - 1)]

    def _metric_depth(self, zbuf: np.ndarray, orthographic: bool) -> np.ndarray:
        """Depth buffer (reversed z, as mujoco.Renderer) to metres; same formulas as mujoco.Renderer."""
        z = zbuf.astype(np.float64)
        far, near = np.float32(self._far), np.float32(self._near)
        if orthographic:
            return (far - z * (far - near)).astype(np.float32)
        c = -(far + near) / (far - near)
        d = -(np.float32(2) * far * near) / (far - near)
        c = np.float32(-0.5) * c - np.float32(0.5)
        d = np.float32(-0.5) * d
        return (d / (z + c)).astype(np.float32)

    def extrinsics(self, camera: str) -> np.ndarray:
        """Camera-to-world 4x4 pose with OpenCV axes (x right, y down, z forward)."""
        cid = self._camera_id(camera)
        pose = np.eye(4)
        pose[:3, :3] = self.data.cam_xmat[cid].reshape(3, 3) @ np.diag([1.0, -1.0, -1.0])
        pose[:3, 3] = self.data.cam_xpos[cid]
        return pose

    def intrinsics(self, camera: str) -> np.ndarray:
        return self._intrinsics[self._checked(camera)]

    def _checked(self, camera: str) -> str:
        if camera not in self._cam_ids:
            extra = f" (the orthographic {HEIGHTMAP_CAMERA!r} camera is rendered by heightmap())" \
                if self._top_id >= 0 else ""
            raise ConfigError(f"unknown camera {camera!r}; valid cameras: {', '.join(self.camera_names)}{extra}")
        return camera

    def _camera_id(self, camera: str) -> int:
        return self._cam_ids[self._checked(camera)]

    # ------------------------------------------------------------------ public
    def render(self, camera: str, *, seg: bool = True, include_robot: bool = True) -> CameraFrame:
        """Render one perspective camera: RGB, metric depth, object segmentation, calibration.

        ``seg=False`` skips the segmentation (``frame.seg`` is None): one pass instead of two.
        ``include_robot=False`` leaves the arm out: the picture a robot takes after moving its arm
        out of view (the perceived planner API uses it; the arm stays where it is).
        """
        cid = self._camera_id(camera)
        with current_context():
            mjr = self._context()
            scene = self._update(cid, hide_robot=not include_robot)
            rgb, zbuf, ids = self._draw(scene, mjr, self.width, self.height, seg)
        depth = self._metric_depth(zbuf, orthographic=False)
        return CameraFrame(
            name=camera,
            rgb=frozen(np.ascontiguousarray(rgb[::-1])),
            depth=frozen(np.ascontiguousarray(depth[::-1])),
            seg=None if ids is None else frozen(np.ascontiguousarray(ids[::-1])),
            intrinsics=self._intrinsics[camera],
            extrinsics=frozen(self.extrinsics(camera)),
        )

    def heightmap(self, *, include_robot: bool = True) -> Heightmap:
        """Top-down heightmap from the orthographic "top" camera (one cell per pixel).

        ``include_robot=False`` leaves the arm and suction tool out (what the table would look like
        without it); by default the heightmap shows what the camera sees, arm included.
        """
        if self._top_id < 0:
            raise SimError(f"the model has no {HEIGHTMAP_CAMERA!r} camera")
        m = self.model
        if self.hm_rows > m.vis.global_.offheight or self.hm_cols > m.vis.global_.offwidth:
            raise SimError(f"heightmap {self.hm_cols}x{self.hm_rows} exceeds the offscreen buffer")
        with current_context():
            mjr = self._context()
            scene = self._update(self._top_id, hide_robot=not include_robot)
            rgb, zbuf, seg = self._draw(scene, mjr, self.hm_cols, self.hm_rows)
        assert seg is not None
        depth = self._metric_depth(zbuf, orthographic=True)
        cam_z = float(self.data.cam_xpos[self._top_id][2])
        table_z = float(self.bounds[2, 0])
        height = np.maximum(cam_z - depth.astype(np.float64) - table_z, 0.0).astype(np.float32)
        # The camera looks down with image-up = +y, so the raw bottom-up GL rows are y ascending
        # (Ravens convention) and columns are x ascending: no flip.
        return Heightmap(height=frozen(height), colormap=frozen(rgb), seg=frozen(seg),
                         pixel_size=self.pixel_size, bounds=frozen(self.bounds.copy()))

    def render_all(self, *, include_robot: bool = True, seg: bool = True, heightmap: bool = True) -> Observation:
        """The three perspective views and the heightmap.

        ``seg=False`` renders the views as RGB + depth in one pass each; ``heightmap=False`` leaves
        the heightmap out (``observation.heightmap`` is None).  Ask only for what you use: on a
        software renderer each pass costs about as much as the physics of a pick-and-place.
        """
        views = MappingProxyType({name: self.render(name, seg=seg) for name in self.camera_names})
        return Observation(views=views,
                           heightmap=self.heightmap(include_robot=include_robot) if heightmap else None)
