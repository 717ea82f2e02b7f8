"""Light copies of the arm's visual meshes, for rendering and compiling at a fraction of the cost.

The Menagerie UR5e's visual OBJ meshes have ~120 k triangles (~360 k vertices as MuJoCo compiles
them).  On a software OpenGL renderer (llvmpipe, this machine's EGL) drawing them dominated every
camera pass (~50 ms of ~75 ms per 640x480 view), and processing them made the first compile of a
process take ~1.1 s.  capmj's arm collides through its capsules and takes its masses and inertias
from the explicit ``<inertial>`` elements, so its visual meshes play no part in the physics: the
world is compiled with simplified copies (same silhouette within ~1 cm, a small fraction of the
triangles; physics bit-identical, tested; ``docs/speed.md``, "Rendering").

Simplification, per mesh: ``trimesh`` welds MuJoCo's per-face vertex copies, vertex clustering on
a fine grid closes the seams that stop an edge-collapse simplifier, then quadric decimation
(``fast-simplification``) removes most of what is left.  The result depends only on the mesh
files and these parameters: it is computed once (~2 s: a full compile plus the decimation), kept in
memory for the process and in ``$CAPMJ_CACHE_DIR`` (default ``~/.cache/capmj``) on disk, keyed by a
hash of the robot's XML, its mesh files and the parameters.  An unwritable cache only costs time.
"""

from __future__ import annotations

import hashlib
import os
import zipfile
from functools import cache
from pathlib import Path
from typing import Callable, Mapping, TypeVar

import mujoco
import numpy as np

from capmj.atomic import atomic_write

CACHE_ENV = "CAPMJ_CACHE_DIR"
T = TypeVar("T")

VISUAL_CLUSTER_M = 0.003
"""Grid size (m) of the vertex clustering of the rendered arm meshes."""
VISUAL_KEEP_FACES = 0.25
"""Share of the clustered triangles the quadric decimation keeps (meshes under 200 are kept whole)."""


def cluster(vertices: np.ndarray, faces: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Vertex-clustering simplification: merge the vertices of each ``cell``-sized grid cell into
    their mean and keep the faces whose three corners land in different cells (once each)."""
    keys = np.floor(vertices / cell).astype(np.int64)
    _, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    n = int(inverse.max()) + 1 if inverse.size else 0
    sums = np.zeros((n, 3))
    np.add.at(sums, inverse, vertices)
    counts = np.bincount(inverse, minlength=n).astype(float)
    new_v = sums / counts[:, None]
    f = inverse[faces]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
    if len(f):
        _, first = np.unique(np.sort(f, axis=1), axis=0, return_index=True)
        f = f[np.sort(first)]
    used = np.unique(f)
    remap = np.full(n, -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return new_v[used], remap[f]


def simplify(vertices: np.ndarray, faces: np.ndarray, cell: float, keep: float,
             min_faces: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """Weld, cluster on a ``cell`` grid, then decimate to ``keep`` of the faces (``min_faces`` and
    smaller meshes are only clustered)."""
    import trimesh

    tm = trimesh.Trimesh(vertices, faces, process=True)  # welds per-face vertex copies
    v, f = cluster(np.asarray(tm.vertices), np.asarray(tm.faces), cell)
    if len(f) > min_faces:
        part = trimesh.Trimesh(v, f, process=False).simplify_quadric_decimation(
            face_count=max(min_faces // 2, int(len(f) * keep)))
        v, f = np.asarray(part.vertices), np.asarray(part.faces)
    return v, f


def _mesh_frame_vertices(model: mujoco.MjModel, mesh: int) -> tuple[np.ndarray, np.ndarray]:
    """A compiled mesh's vertices moved back into its file's frame (scale applied) and its faces.

    MuJoCo stores mesh vertices relative to the mesh's inertial frame (``mesh_pos``/``mesh_quat``)
    and folds that offset into the geom pose; user vertices given back must undo it."""
    va, vn = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
    fa, fn = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, model.mesh_quat[mesh])
    v = np.asarray(model.mesh_vert[va:va + vn], dtype=np.float64) @ rot.reshape(3, 3).T + model.mesh_pos[mesh]
    return v, np.asarray(model.mesh_face[fa:fa + fn], dtype=np.int64)


def cache_dir() -> Path:
    """Where capmj keeps derived data between processes (``$CAPMJ_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/capmj``, else ``~/.cache/capmj``)."""
    if os.environ.get(CACHE_ENV, "").strip():
        return Path(os.environ[CACHE_ENV].strip())
    base = os.environ.get("XDG_CACHE_HOME", "").strip() or str(Path.home() / ".cache")
    return Path(base) / "capmj"


def _cache_key(xml_path: str) -> str:
    """Hash of the XML, every mesh file it names and the simplification parameters."""
    xml = Path(xml_path)
    spec = mujoco.MjSpec.from_file(xml_path)  # parsing only: cheap
    h = hashlib.sha256(f"{VISUAL_CLUSTER_M}|{VISUAL_KEEP_FACES}|{mujoco.__version__}".encode())
    h.update(xml.read_bytes())
    for mesh in spec.meshes:
        h.update(mesh.name.encode())
        h.update((xml.parent / spec.meshdir / mesh.file).read_bytes())
    return h.hexdigest()[:24]


def _compute(xml_path: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    model = mujoco.MjSpec.from_file(xml_path).compile()
    return {model.mesh(i).name: simplify(*_mesh_frame_vertices(model, i), VISUAL_CLUSTER_M, VISUAL_KEEP_FACES)
            for i in range(model.nmesh)}


@cache
def _light_meshes(xml_path: str) -> dict[str, tuple[list[float], list[int]]]:
    """Each mesh's flat vertex and face lists, as ``MjsMesh.uservert``/``userface`` take them:
    converted once per process, not at every world build."""
    return {name: (v.ravel().tolist(), f.ravel().tolist()) for name, (v, f) in _stored_meshes(xml_path).items()}


def cached_arrays(name: str, compute: Callable[[], dict[str, np.ndarray]],
                  decode: Callable[[Mapping[str, np.ndarray]], T]) -> T:
    """``decode`` of the arrays stored as ``name``.npz in :func:`cache_dir`, else of ``compute()``'s,
    which are stored there first.  A missing or damaged file is recomputed; the file is written
    with :func:`capmj.atomic.atomic_write`, so concurrent workers never read half of one; an
    unwritable cache only costs time."""
    path = cache_dir() / f"{name}.npz"
    try:
        with np.load(path) as z:
            return decode(z)
    except (OSError, KeyError, ValueError, zipfile.BadZipFile):  # missing or damaged: recompute
        pass
    arrays = compute()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_write(path, "wb") as f:
            np.savez(f, **arrays)  # type: ignore[arg-type]
    except OSError:
        pass
    return decode(arrays)


def _stored_meshes(xml_path: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The simplified meshes from the disk cache, else computed (and stored there)."""
    def compute() -> dict[str, np.ndarray]:
        meshes = _compute(xml_path)
        arrays: dict[str, np.ndarray] = {"names": np.array(list(meshes))}
        for k, (v, f) in enumerate(meshes.values()):
            arrays[f"v{k}"], arrays[f"f{k}"] = v, f
        return arrays

    def decode(z: Mapping[str, np.ndarray]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        return {str(n): (z[f"v{k}"], z[f"f{k}"]) for k, n in enumerate(z["names"])}

    return cached_arrays(f"ur5e-visual-{_cache_key(xml_path)}", compute, decode)


def use_light_meshes(spec: mujoco.MjSpec, xml_path: str) -> None:
    """Replace every mesh of ``spec`` (loaded from ``xml_path``) by its simplified copy, in place."""
    light = _light_meshes(xml_path)
    for mesh in spec.meshes:
        vert, face = light[mesh.name]
        mesh.file = ""
        mesh.scale = [1.0, 1.0, 1.0]
        mesh.uservert = vert
        mesh.userface = face


__all__ = ["CACHE_ENV", "VISUAL_CLUSTER_M", "VISUAL_KEEP_FACES", "cache_dir", "cached_arrays", "cluster", "simplify",
           "use_light_meshes"]
