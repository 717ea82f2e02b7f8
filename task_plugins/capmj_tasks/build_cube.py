"""Generated task 2: build-cube."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks.protocol import OracleGoal, Scene, Verdict
from capmj.tasks.spawn import Spawner, pick_colors

from capmj_tasks.common import EXTENDED, BenchTask, verdict
from capmj_tasks.structures import Judgement, check_layers, layer_goal

PITCH = 0.045
"""Neighbour pitch (m) of the oracle's layers: the middle of the allowed 0.04–0.05 m."""
PITCH_RANGE = (0.04, 0.05)
SIDES = (2, 2)


class BuildCube(BenchTask):
    """Build a 2 × 2 × 2 cube of small blocks in a zone.

    Task Description:
        "Construct a 2*2*2 cube structure in the zone using 8 blocks of the same color."  One
        zone (0.12 m square) and 8 small blocks of one colour (not the zone's).

    Randomizations:
        The zone and block colours (distinct), all poses and yaws (collision-free, no block in
        the zone).  The text names no colour or number that varies: the spec's text is fixed.

    Success Conditions:
        Two layers of 4 blocks, each a 2 × 2 grid (``predicates.is_layer``: neighbour pitch
        0.04–0.05 m, aligned within 0.015 m), every centre in the zone (``predicates.in_zone``):
        the lower upright on the table, the upper at one block height (± 0.015 m) with each block resting
        on exactly one lower block and within 0.015 m of it in xy.  Progress: blocks per layer,
        the grid checks and every block's placement, as a share of all of them.
    """

    name = "build-cube"
    tags = EXTENDED

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        zc, bc = pick_colors(rng, 2)
        sp = Spawner(rng)
        zone = sp.zone(zc)
        blocks = [sp.block(bc, "small") for _ in range(8)]
        return Scene(sp.objects, "Construct a 2*2*2 cube structure in the zone using 8 blocks of the same color.",
                     {"zone": zone.obj_id, "blocks": [b.obj_id for b in blocks]})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        """Lower layer, then upper layer, on the same grid centred on the zone and turned with it."""
        zone = scene.by_id(scene.info["zone"])
        ids = list(scene.info["blocks"])
        return [layer_goal(ids[:4], zone.pos, zone.yaw, 2, 0, PITCH), layer_goal(ids[4:], zone.pos, zone.yaw, 2, 1, PITCH)]

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        j = Judgement()
        check_layers(state, scene.info["blocks"], scene.info["zone"], SIDES, PITCH_RANGE, stacked=True, j=j)
        if j.ok:
            j.diagnostics.append("2x2x2 cube built in the zone")
        return verdict(j.met, j.total, j.ok, j.diagnostics)


TASK = BuildCube()
