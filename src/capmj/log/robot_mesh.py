"""The UR5e's visual meshes for episode logs: one coarse, coloured triangle mesh per link.

The meshes are the world's visual meshes as MuJoCo compiled them (:meth:`capmj.sim.world.World.mesh`
of the visual geoms, group 2; already the light copies of :mod:`capmj.sim.visual_mesh`), moved into their body frame with the geom's pose, so a
link mesh is drawn correctly by the link's world transform alone.  Each link's mesh is welded and
simplified in two steps, per visual geom (so colour boundaries stay sharp): vertex clustering on a
fine grid closes the seams that stop an edge-collapse simplifier, then ``trimesh``'s quadric
decimation (``fast-simplification``) removes most of what is left, coarser than for the cameras:
a log should stay small, and a few thousand triangles keep the silhouette and the blue joint caps.  Vertex normals come from ``trimesh`` (rerun draws a mesh without normals
unlit).

The result depends only on the model's meshes, so it is computed once per machine: kept in memory
for the process and on disk in capmj's cache directory (:func:`capmj.sim.visual_mesh.cache_dir`),
keyed by a hash of everything it is computed from.  A bench worker, which logs episodes from a
fresh process, so loads ~50 kB instead of importing trimesh and simplifying (~1 s per worker).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING, Mapping

import numpy as np

from capmj.sim.pose import quat_to_mat
from capmj.sim.visual_mesh import cached_arrays, simplify

if TYPE_CHECKING:
    from capmj.sim.parts import GeomPart as Part
    from capmj.sim.world import World

VISUAL_GROUP = 2
"""MuJoCo geom group of the Menagerie arm's visual (non-colliding) meshes."""
CLUSTER_M = 0.006
"""Grid size (m) of the vertex clustering: vertices in one cell (and of one geom) merge."""
KEEP_FACES = 0.08
"""Share of the clustered triangles the quadric decimation aims to keep (it keeps more where the
mesh has open boundaries)."""
MIN_FACES = 64
"""Geoms with at most this many clustered triangles are not decimated."""


@dataclass(frozen=True, eq=False)
class LinkMesh:
    """One link's visual mesh in the link's body frame (float32 arrays, read-only)."""

    body: str
    vertices: np.ndarray      # (V, 3)
    faces: np.ndarray         # (F, 3) uint32
    normals: np.ndarray       # (V, 3)
    colors: np.ndarray        # (V, 4) uint8 RGBA


def _geom_part(world: "World", g: "Part") -> tuple[np.ndarray, np.ndarray]:
    """Vertices (body frame) and faces of a mesh geom."""
    assert g.mesh is not None
    v, f = world.mesh(g.mesh)
    return v @ quat_to_mat(g.quat).T + np.asarray(g.pos), f


def _geom_rgba(g: "Part") -> np.ndarray:
    rgba = g.material_rgba if g.material_rgba is not None else g.rgba
    return np.clip(np.round(np.asarray(rgba) * 255), 0, 255).astype(np.uint8)


GeomPart = tuple[np.ndarray, np.ndarray, np.ndarray]
"""A visual mesh geom's vertices (body frame), faces and RGBA."""


def _visual_parts(world: "World", bodies: tuple[str, ...]) -> list[tuple[str, list[GeomPart]]]:
    """Each body's visual mesh geoms, as the simplification takes them."""
    out = []
    for name in bodies:
        geoms = [g for g in world.body_parts(name) if g.kind == "mesh" and g.group == VISUAL_GROUP]
        out.append((name, [(*_geom_part(world, g), _geom_rgba(g)) for g in geoms]))
    return out


def _simplified(parts: list[tuple[str, list[GeomPart]]], cell: float) -> list[LinkMesh]:
    import trimesh

    out: list[LinkMesh] = []
    for name, geoms in parts:
        verts, faces, norms, cols = [], [], [], []
        offset = 0
        for v, f, rgba in geoms:
            sv, sf = simplify(v, f, cell, KEEP_FACES, min_faces=MIN_FACES)
            if not len(sf):
                continue
            verts.append(sv)
            faces.append(sf + offset)
            norms.append(np.asarray(trimesh.Trimesh(sv, sf, process=False).vertex_normals))
            cols.append(np.tile(rgba, (len(sv), 1)))
            offset += len(sv)
        if not faces:
            continue
        out.append(_link_mesh(name, np.concatenate(verts).astype(np.float32), np.concatenate(faces).astype(np.uint32),
                              np.concatenate(norms).astype(np.float32), np.concatenate(cols)))
    return out


def _link_mesh(body: str, *arrays: np.ndarray) -> LinkMesh:
    for a in arrays:
        a.flags.writeable = False
    return LinkMesh(body, *arrays)


def link_meshes(world: "World", bodies: tuple[str, ...], cell: float = CLUSTER_M) -> list[LinkMesh]:
    """The simplified visual mesh of each body in ``bodies`` that has visual mesh geoms."""
    return _simplified(_visual_parts(world, bodies), cell)


def _package_version(name: str) -> str:
    try:
        return version(name)
    except PackageNotFoundError:
        return "?"


def _disk_key(parts: list[tuple[str, list[GeomPart]]], cell: float) -> str:
    """Hash of the simplification's inputs, its parameters and the libraries that compute it."""
    h = hashlib.sha256(f"{cell}|{KEEP_FACES}|{MIN_FACES}|{_package_version('trimesh')}|"
                       f"{_package_version('fast-simplification')}|{np.__version__}".encode())
    for name, geoms in parts:
        h.update(f"|{name}:{len(geoms)}".encode())
        for a in (a for g in geoms for a in g):
            h.update(f"{a.dtype}{a.shape}".encode())
            h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:24]


_FIELDS = ("vertices", "faces", "normals", "colors")


def _stored_link_meshes(world: "World", bodies: tuple[str, ...], cell: float) -> list[LinkMesh]:
    """:func:`link_meshes` from the disk cache, else computed (and stored there)."""
    parts = _visual_parts(world, bodies)

    def compute() -> dict[str, np.ndarray]:
        meshes = _simplified(parts, cell)
        arrays: dict[str, np.ndarray] = {"names": np.array([lm.body for lm in meshes])}
        for k, lm in enumerate(meshes):
            arrays.update({f"{f}{k}": getattr(lm, f) for f in _FIELDS})
        return arrays

    def decode(z: Mapping[str, np.ndarray]) -> list[LinkMesh]:
        return [_link_mesh(str(n), *(np.array(z[f"{f}{k}"]) for f in _FIELDS)) for k, n in enumerate(z["names"])]

    return cached_arrays(f"ur5e-log-links-{_disk_key(parts, cell)}", compute, decode)


_CACHE: dict[tuple[int, int, tuple[str, ...], float], list[LinkMesh]] = {}


def cached_link_meshes(world: "World", bodies: tuple[str, ...], cell: float = CLUSTER_M) -> list[LinkMesh]:
    """:func:`link_meshes`, from memory after the first call of a process (every episode's world
    holds the same arm), else from the disk cache, else computed."""
    key = (*world.mesh_size, tuple(bodies), float(cell))
    if key not in _CACHE:
        _CACHE[key] = _stored_link_meshes(world, bodies, cell)
    return _CACHE[key]


__all__ = ["CLUSTER_M", "KEEP_FACES", "LinkMesh", "VISUAL_GROUP", "cached_link_meshes", "link_meshes"]
