"""Task A: stack-all-blocks-on-a-zone."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks.protocol import OracleGoal, Scene, Verdict
from capmj.tasks.spawn import Spawner, pick_colors

from capmj_tasks.common import BenchTask, check_stack, stack_goals, verdict


class StackAllBlocksOnAZone(BenchTask):
    """Stack every block of the table in the named zone.

    Task Description:
        "Stack all blocks in the {color} zone."  One target zone, one distractor zone of another
        colour, and 2–5 small blocks of distinct colours.

    Randomizations:
        Number of blocks (2–5), block colours (distinct), colours of the two zones (distinct),
        all poses and yaws (collision-free).

    Success Conditions:
        All blocks form one stack (``predicates.is_stack``: axis within 0.02 m, each resting on
        the previous ± 0.015 m, none tilted > 15°) whose blocks all have their centres inside the
        target zone.  Order does not matter.  Progress = tallest valid stack in the zone / blocks.
    """

    name = "stack-all-blocks-on-a-zone"

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        sp = Spawner(rng)
        zc, dc = pick_colors(rng, 2)
        zone = sp.zone(zc)
        dist = sp.zone(dc)
        n = int(rng.integers(2, 6))
        blocks = [sp.block(c, "small") for c in pick_colors(rng, n)]
        return Scene(sp.objects, f"Stack all blocks in the {zc} zone.",
                     {"zone": zone.obj_id, "distractor_zones": [dist.obj_id], "blocks": [b.obj_id for b in blocks]})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        return stack_goals(scene, scene.info["zone"], scene.info["blocks"])

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        ids = scene.info["blocks"]
        rep = check_stack(state, ids, scene.info["zone"])
        return verdict(len(rep.tower), len(ids), rep.ok, rep.diagnostics)


TASK = StackAllBlocksOnAZone()
