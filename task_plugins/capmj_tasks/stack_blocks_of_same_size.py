"""Task B: stack-blocks-of-same-size."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks.protocol import OracleGoal, Scene, Verdict
from capmj.tasks.spawn import Spawner, pick_colors

from capmj_tasks.common import BenchTask, check_stack, shuffled, stack_goals, verdict


class StackBlocksOfSameSize(BenchTask):
    """Stack the big blocks in one named zone and the small blocks in the other.

    Task Description:
        "Stack blocks of the same size in the {c1} zone and {c2} zone respectively."  Two target
        zones (c1 ≠ c2), one distractor zone of a third colour, 1–4 big and 1–4 small blocks.

    Randomizations:
        Numbers of big (1–4) and small (1–4) blocks, block colours (distinct), zone colours
        (distinct), spawn order of the blocks (ids do not reveal sizes), all poses and yaws.

    Success Conditions:
        The big blocks form one stack inside one of the two target zones and the small blocks
        one stack inside the other (either assignment is accepted; the oracle puts big in c1).
        Stacks as ``predicates.is_stack``.  Progress = blocks on the tallest valid partial
        stacks (best assignment) / all blocks.
    """

    name = "stack-blocks-of-same-size"

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        sp = Spawner(rng)
        c1, c2, c3 = pick_colors(rng, 3)
        z1, z2, z3 = sp.zone(c1), sp.zone(c2), sp.zone(c3)
        nb, ns = int(rng.integers(1, 5)), int(rng.integers(1, 5))
        sizes = shuffled(rng, ["big"] * nb + ["small"] * ns)
        blocks = [sp.block(c, s) for c, s in zip(pick_colors(rng, nb + ns), sizes)]
        return Scene(
            sp.objects,
            f"Stack blocks of the same size in the {c1} zone and {c2} zone respectively.",
            {"zones": [z1.obj_id, z2.obj_id], "distractor_zones": [z3.obj_id],
             "big": [b.obj_id for b in blocks if b.size == "big"],
             "small": [b.obj_id for b in blocks if b.size == "small"]},
        )

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        z1, z2 = scene.info["zones"]
        return stack_goals(scene, z1, scene.info["big"]) + stack_goals(scene, z2, scene.info["small"])

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        z1, z2 = scene.info["zones"]
        big, small = scene.info["big"], scene.info["small"]
        n = len(big) + len(small)
        best = None
        for zb, zs in ((z1, z2), (z2, z1)):
            rb = check_stack(state, big, zb, what="big blocks")
            rs = check_stack(state, small, zs, what="small blocks")
            score = len(rb.tower) + len(rs.tower) + (n + 1) * (rb.ok + rs.ok)
            if best is None or score > best[0]:
                best = (score, rb, rs)
        _, rb, rs = best
        return verdict(len(rb.tower) + len(rs.tower), n, rb.ok and rs.ok, rb.diagnostics + rs.diagnostics)


TASK = StackBlocksOfSameSize()
