"""The arm's simplified visual meshes: physics unchanged bit for bit, the silhouette kept."""

from __future__ import annotations

import numpy as np
import pytest

import capmj.sim.robot as robot
from capmj.sim.objects import ObjectSpec
from capmj.sim.primitives import Primitives
from capmj.sim.visual_mesh import cluster
from capmj.sim.world import World

SPECS = [ObjectSpec(1, "block", "red", (0.5, 0.1, 0.02), 0.3, "small"),
         ObjectSpec(2, "block", "blue", (0.45, -0.15, 0.02), 0.0, "small")]


def _run(world: World) -> np.ndarray:
    prims = Primitives(world)
    assert prims.pick_and_place(np.array([0.5, 0.1]), np.array([0.45, -0.15, 0.06]), 0.5).ok
    return np.concatenate([world.data.qpos, world.data.qvel])


def test_light_visual_meshes_leave_the_physics_bit_identical(monkeypatch: pytest.MonkeyPatch) -> None:
    light = World(SPECS)
    monkeypatch.setattr(robot, "use_light_meshes", lambda spec, path: None)
    full = World(SPECS)
    assert light.model.nmeshface * 5 < full.model.nmeshface  # the copies really are lighter
    np.testing.assert_array_equal(light.model.body_mass, full.model.body_mass)
    np.testing.assert_array_equal(light.model.body_inertia, full.model.body_inertia)
    assert np.array_equal(_run(light), _run(full))


def test_light_meshes_keep_each_links_extent_within_a_centimetre(monkeypatch: pytest.MonkeyPatch) -> None:
    light = World(SPECS).model
    monkeypatch.setattr(robot, "use_light_meshes", lambda spec, path: None)
    full = World(SPECS).model

    def extent(model, g: int) -> np.ndarray:  # noqa: ANN001 - body-frame bounding box of a mesh geom
        import mujoco

        mid = model.geom_dataid[g]
        v = model.mesh_vert[model.mesh_vertadr[mid]:model.mesh_vertadr[mid] + model.mesh_vertnum[mid]]
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, model.geom_quat[g])
        p = v @ rot.reshape(3, 3).T + model.geom_pos[g]
        return np.concatenate([p.min(axis=0), p.max(axis=0)])

    meshes = [g for g in range(full.ngeom) if full.geom_dataid[g] >= 0 and full.geom_type[g] == 7]
    assert meshes
    worst = max(float(np.abs(extent(light, g) - extent(full, g)).max()) for g in meshes)
    assert worst < 0.012


def test_cluster_merges_vertices_of_a_cell_and_drops_collapsed_faces() -> None:
    v = np.array([[0.0, 0, 0], [0.0001, 0, 0], [1, 0, 0], [0, 1, 0]])
    f = np.array([[0, 1, 2], [0, 2, 3], [1, 2, 3]])
    nv, nf = cluster(v, f, 0.01)
    assert len(nv) == 3 and len(nf) == 1  # vertices 0 and 1 merge; face 0 collapses, 1 and 2 coincide


def test_light_meshes_are_cached_on_disk_and_a_damaged_cache_is_recomputed(
        tmp_path, monkeypatch: pytest.MonkeyPatch) -> None:  # noqa: ANN001
    from capmj.sim import visual_mesh

    monkeypatch.setenv(visual_mesh.CACHE_ENV, str(tmp_path))
    xml = str(robot.robot_source().xml_path)
    compute = visual_mesh._stored_meshes  # the disk cache, below the in-process memo
    first = compute(xml)
    files = list(tmp_path.glob("ur5e-visual-*.npz"))
    assert len(files) == 1
    calls = []
    monkeypatch.setattr(visual_mesh, "_compute", lambda path: calls.append(path) or first)
    again = compute(xml)
    assert not calls and again.keys() == first.keys()
    assert all(np.array_equal(again[k][0], first[k][0]) and np.array_equal(again[k][1], first[k][1]) for k in first)
    files[0].write_bytes(b"PK\x03\x04 damaged")
    compute(xml)
    assert calls == [xml]
