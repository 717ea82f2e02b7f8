# expect: runtime:not_solved_at_reset
# goal: Put every block in the zone of its color.
"""Subtly broken: the blocks spawn inside their zones."""

from __future__ import annotations

import numpy as np

from capmj.sim.objects import ObjectSpec
from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Target, Verdict
from capmj.tasks.spawn import Spawner, pick_colors


class PutBlocksInZoneOfSameColor:
    """Put every block in the zone of its colour.

    Task Description:
        "Put every block in the zone of its color."  2-3 zones of distinct colours and one small
        block of each zone colour.

    Randomizations:
        Number of zones, colours, all poses and yaws.

    Success Conditions:
        Every block's centre is inside the zone of its colour (predicates.in_zone).
    """

    name = "put-blocks-in-zone-of-same-color"
    tags = frozenset({"generated-by-llm"})

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        k = int(rng.integers(2, 4))
        cols = pick_colors(rng, k)
        sp = Spawner(rng)
        zones = [sp.zone(c) for c in cols]
        blocks = [ObjectSpec(k + i + 1, "block", z.color, (z.pos[0], z.pos[1], 0.02), size="small")
                  for i, z in enumerate(zones)]
        pairs = [[b.obj_id, z.obj_id] for b, z in zip(blocks, zones)]
        return Scene(tuple(zones) + tuple(blocks), "Put every block in the zone of its color.", {"pairs": pairs})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        pairs = scene.info["pairs"]
        targets = []
        for b, z in pairs:
            zone, block = scene.by_id(z), scene.by_id(b)
            targets.append(Target((zone.pos[0], zone.pos[1], block.height / 2)))
        n = len(pairs)
        matches = tuple(tuple(int(i == j) for j in range(n)) for i in range(n))
        return [OracleGoal(tuple(b for b, _ in pairs), tuple(targets), matches, metric="zone",
                           zone_size=0.12)]

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        met, diags = 0, []
        for b, z in scene.info["pairs"]:
            if P.in_zone(state, b, z):
                met += 1
            else:
                diags.append(f"block {b} is not in zone {z}")
        n = len(scene.info["pairs"])
        return Verdict(met == n, met / n if met < n else 1.0, tuple(diags) or ("every block in its zone",))


TASK = PutBlocksInZoneOfSameColor()
