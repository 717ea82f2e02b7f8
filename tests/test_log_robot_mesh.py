"""The arm's link meshes for episode logs: stored on disk, so a fresh process need not recompute them."""

from __future__ import annotations

import numpy as np
import pytest

from capmj.log import robot_mesh
from capmj.sim.robot import SUCTION_BODY
from capmj.sim.visual_mesh import CACHE_ENV
from capmj.sim.world import World


def test_link_meshes_are_cached_on_disk_equal_to_computed_and_a_damaged_cache_is_recomputed(
        tmp_path, monkeypatch: pytest.MonkeyPatch) -> None:  # noqa: ANN001
    monkeypatch.setenv(CACHE_ENV, str(tmp_path))
    m = World(())
    bodies = tuple(n for n in m.link_names if n != SUCTION_BODY)
    first = robot_mesh._stored_link_meshes(m, bodies, robot_mesh.CLUSTER_M)  # the disk cache, below the memo: computed
    files = list(tmp_path.glob("ur5e-log-links-*.npz"))
    assert len(files) == 1 and first
    calls = []
    monkeypatch.setattr(robot_mesh, "_simplified", lambda parts, cell: calls.append(cell) or first)
    again = robot_mesh._stored_link_meshes(m, bodies, robot_mesh.CLUSTER_M)
    assert not calls
    for a, b in zip(again, first, strict=True):  # loaded == computed, bit for bit
        assert a.body == b.body
        for f in ("vertices", "faces", "normals", "colors"):
            x, y = getattr(a, f), getattr(b, f)
            assert x.dtype == y.dtype and np.array_equal(x, y) and not x.flags.writeable
    files[0].write_bytes(b"PK\x03\x04 damaged")
    robot_mesh._stored_link_meshes(m, bodies, robot_mesh.CLUSTER_M)
    assert calls == [robot_mesh.CLUSTER_M]
