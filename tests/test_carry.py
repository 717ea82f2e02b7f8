"""The carry's sloped transit (capmj.sim.carry) for picks where the full transit height is out of reach."""

from __future__ import annotations

import numpy as np

from capmj.sim.carry import corridor, reach_height
from capmj.sim.objects import ObjectSpec
from capmj.sim.primitives import Primitives
from capmj.sim.world import World

COLORS = ("red", "blue", "green", "yellow", "orange", "purple", "pink", "cyan")


def tower_world(tower_xy: tuple[float, float], levels: int, block_xy: tuple[float, float]) -> World:
    """A tower of ``levels`` small blocks (ids 1..levels) and one loose small block (last id)."""
    specs = [ObjectSpec(k + 1, "block", COLORS[k], (tower_xy[0], tower_xy[1], 0.02 + 0.04 * k), size="small")
             for k in range(levels)]
    specs.append(ObjectSpec(levels + 1, "block", COLORS[levels], (block_xy[0], block_xy[1], 0.02), size="small"))
    w = World(specs)
    w.settle()
    return w


def test_far_corner_pick_onto_a_tall_tower_carries_on_a_slope() -> None:
    """Above the far corner the full transit height over a seven-block tower (plus the carried
    block's hang) is out of reach; only the tower, at the place end, needs clearing, so the block
    goes on top of the tower and the tower stays put."""
    w = tower_world((0.413, 0.012), 7, (0.695, 0.398))
    p = Primitives(w)
    top = p.transit_height(exclude=8, hang=0.04)
    assert reach_height(p.motion.ik, w.arm_ctrl(), np.array([0.695, 0.398]), 0.0, top, 0.0) < top
    before = {i: np.array(w.pose(i).pos) for i in range(1, 8)}
    res = p.pick_and_place(np.array(w.pose(8).pos), np.array([0.413, 0.012, 0.02 + 0.04 * 7]), 0.0)
    assert res.ok, res.message
    assert np.linalg.norm(np.array(w.pose(8).pos)[:2] - (0.413, 0.012)) < 0.01
    assert all(np.linalg.norm(np.array(w.pose(i).pos) - before[i]) < 0.005 for i in range(1, 8))


def test_corridor_names_only_what_the_carried_footprint_passes_over() -> None:
    """A carry along y passes over the block in its way (entering and leaving where the grown box
    says) and not over one 20 cm to the side."""
    w = World([ObjectSpec(1, "block", "red", (0.5, 0.0, 0.02), size="small"),
               ObjectSpec(2, "block", "blue", (0.7, 0.0, 0.02), size="small")])
    hits = corridor(w, np.array([0.5, -0.3]), np.array([0.5, 0.3]), radius=0.03)
    assert len(hits) == 1
    s_in, s_out, top = hits[0]
    half = 0.02 + 0.03  # half the block's side plus the radius
    assert abs(s_in - (0.3 - half) / 0.6) < 0.01 and abs(s_out - (0.3 + half) / 0.6) < 0.01
    assert abs(top - 0.04) < 0.002
