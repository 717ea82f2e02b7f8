"""Generated task 1: build-rectangular-pyramid."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks.protocol import OracleGoal, Scene, Verdict
from capmj.tasks.spawn import Spawner, pick_colors

from capmj_tasks.common import EXTENDED, BenchTask, verdict
from capmj_tasks.structures import Judgement, check_layers, layer_goal

PITCH = 0.05
"""Neighbour pitch (m) of the oracle's grids: 1 cm between blocks, so each upper block, centred
on four, overlaps each of them by 1.5 × 1.5 cm."""
PITCH_RANGE = (0.04, 0.06)
SIDES = (3, 2, 1)
ZONE_SCALE = 2.0


class BuildRectangularPyramid(BenchTask):
    """Build a 9-4-1 pyramid of small blocks in a double-size zone.

    Task Description:
        "Construct a 9-4-1 rectangular pyramid structure in the zone using 14 blocks of the same
        color."  One 2× zone (0.24 m square) and 14 small blocks of one colour (not the zone's).

    Randomizations:
        The zone and block colours (distinct), all poses and yaws (collision-free, no block in
        the zone).  The text names no colour or number that varies: the spec's text is fixed.

    Success Conditions:
        Layer 1: 9 blocks upright on the table with centres in the zone forming a 3 × 3 grid
        (``predicates.is_layer``: neighbour pitch 0.04–0.06 m, rows and columns aligned within
        0.015 m).  Layer 2: 4 blocks at one block height
        (± 0.015 m) forming a 2 × 2 grid, each resting on four layer-1 blocks
        (``predicates.supporters``: z gap ± 0.015 m, footprints overlapping).  Layer 3: one block
        resting on the four of layer 2.  Every centre in the zone (``predicates.in_zone``).  Progress: blocks per layer, the grid checks and every
        block's support, as a share of all of them.
    """

    name = "build-rectangular-pyramid"
    tags = EXTENDED

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        zc, bc = pick_colors(rng, 2)
        sp = Spawner(rng)
        zone = sp.zone(zc, scale=ZONE_SCALE)
        blocks = [sp.block(bc, "small") for _ in range(sum(s * s for s in SIDES))]
        return Scene(sp.objects,
                     "Construct a 9-4-1 rectangular pyramid structure in the zone using 14 blocks of the same color.",
                     {"zone": zone.obj_id, "blocks": [b.obj_id for b in blocks]})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        """Bottom-up, one goal per layer; grids centred on the zone and turned with it."""
        zone = scene.by_id(scene.info["zone"])
        ids = list(scene.info["blocks"])
        goals, start = [], 0
        for level, side in enumerate(SIDES):
            goals.append(layer_goal(ids[start:start + side * side], zone.pos, zone.yaw, side, level, PITCH))
            start += side * side
        return goals

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        j = Judgement()
        check_layers(state, scene.info["blocks"], scene.info["zone"], SIDES, PITCH_RANGE, stacked=False, j=j)
        if j.ok:
            j.diagnostics.append("9-4-1 pyramid built in the zone")
        return verdict(j.met, j.total, j.ok, j.diagnostics)


TASK = BuildRectangularPyramid()
