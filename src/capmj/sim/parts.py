"""What the layers above ``sim`` may read of a compiled model: geom parts, robot links, meshes.

Plain frozen records copied out of ``MjModel``, so that loggers and exporters draw an episode
without holding MuJoCo's structs or knowing its enums and address tables (``geom_dataid``,
``mesh_vertadr``…): :class:`~capmj.sim.world.World` hands these out, and it is the only door to
``MjModel``/``MjData`` above ``sim/`` (``tests/test_layers.py`` checks that).  Everything here is
static: it depends on the model, never on the state.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

GEOM_KINDS = {
    int(mujoco.mjtGeom.mjGEOM_BOX): "box",
    int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder",
    int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere",
    int(mujoco.mjtGeom.mjGEOM_MESH): "mesh",
}
"""The geom types capmj's worlds use, by name; any other type is ``"other"``."""


def _frozen(a: Any) -> np.ndarray:
    """A read-only copy in MuJoCo's own dtype (colours are float32 there: a float64 copy would
    round differently when turned into bytes)."""
    out = np.array(a)
    out.flags.writeable = False
    return out


@dataclass(frozen=True, eq=False)
class GeomPart:
    """One geom of a body, in the body's frame.

    ``size`` is MuJoCo's (box: half extents; cylinder: radius, half length; sphere: radius);
    ``quat`` is (w, x, y, z); ``rgba`` the geom's own colour and ``material_rgba`` its material's
    (``None`` without a material: the renderer draws the material's colour where there is one).
    """

    geom: int
    kind: str
    size: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    rgba: np.ndarray
    material_rgba: np.ndarray | None
    group: int
    mesh: int | None
    """Index of the geom's mesh (``World.mesh``) for a mesh geom, else ``None``."""


@dataclass(frozen=True)
class Link:
    """A body of the robot: its parent body, how many joints move it, and its pose in the parent."""

    name: str
    parent: str
    joints: int
    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float]


def geom_part(model: mujoco.MjModel, g: int) -> GeomPart:
    mat = int(model.geom_matid[g])
    mesh = int(model.geom_dataid[g]) if int(model.geom_type[g]) == mujoco.mjtGeom.mjGEOM_MESH else -1
    return GeomPart(int(g), GEOM_KINDS.get(int(model.geom_type[g]), "other"), _frozen(model.geom_size[g]),
                    _frozen(model.geom_pos[g]), _frozen(model.geom_quat[g]), _frozen(model.geom_rgba[g]),
                    _frozen(model.mat_rgba[mat]) if mat >= 0 else None, int(model.geom_group[g]),
                    mesh if mesh >= 0 else None)


def body_parts(model: mujoco.MjModel, body: int) -> tuple[GeomPart, ...]:
    """The geoms of one body, in model order."""
    return tuple(geom_part(model, int(g)) for g in np.flatnonzero(model.geom_bodyid == body))


def link(model: mujoco.MjModel, name: str) -> Link:
    b = model.body(name)
    return Link(name, model.body(int(b.parentid[0])).name, int(model.body_jntnum[b.id]),
                tuple(float(v) for v in b.pos), tuple(float(v) for v in b.quat))  # type: ignore[arg-type]


def mesh(model: mujoco.MjModel, index: int) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (float64, the mesh's frame as compiled) and triangles (int64) of one mesh."""
    va, vn = int(model.mesh_vertadr[index]), int(model.mesh_vertnum[index])
    fa, fn = int(model.mesh_faceadr[index]), int(model.mesh_facenum[index])
    return (np.asarray(model.mesh_vert[va:va + vn], dtype=np.float64),
            np.asarray(model.mesh_face[fa:fa + fn], dtype=np.int64))


__all__ = ["GEOM_KINDS", "GeomPart", "Link", "body_parts", "geom_part", "link", "mesh"]
