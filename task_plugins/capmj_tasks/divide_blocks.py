"""Generated task 6: divide-blocks."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Verdict
from capmj.tasks.spawn import Spawner, pick_colors
from capmj_tasks.common import EXTENDED, BenchTask, label, stack_goals, verdict


class DivideBlocks(BenchTask):
    """Divide the blocks into groups of k and stack each group in its own zone.

    Task Description:
        "Divide the blocks into groups of {k} and stack each group (also including the group with
        block number less than {k}) in a different zone."  7–8 small blocks of distinct colours
        and ceil(n / k) zones of distinct colours, so every group has a zone of its own.  Which
        block goes into which group is free.  The spec's wording is kept when k divides n (eight
        blocks in pairs): then there is simply no smaller group.
    Randomizations:
        n ∈ {7, 8}, k ∈ {2, 3}, block and zone colours, all poses and yaws (no block starts in a
        zone).
    Success Conditions:
        Every zone holds exactly one stack (``predicates.zone_stacks``: the blocks whose centre is
        in the zone form one ``is_stack`` tower) and the stack sizes, sorted, are k, …, k and
        n mod k when that is nonzero (``predicates.group_sizes``); so every block is in a stack.
        Progress = Σ min(tower height, group size) over zones and groups both sorted by size,
        divided by n.
    """

    name = "divide-blocks"
    tags = EXTENDED

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        n = int(rng.integers(7, 9))
        k = int(rng.integers(2, 4))
        sizes = P.group_sizes(n, k)
        sp = Spawner(rng)
        zones = [sp.zone(c) for c in pick_colors(rng, len(sizes))]
        blocks = [sp.block(c, "small") for c in pick_colors(rng, n)]
        goal = (f"Divide the blocks into groups of {k} and stack each group (also including the group with "
                f"block number less than {k}) in a different zone.")
        return Scene(sp.objects, goal, {"k": k, "zones": [z.obj_id for z in zones],
                                        "blocks": [b.obj_id for b in blocks], "group_sizes": sizes})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        """Blocks in id order cut into the groups (largest first), one stack per zone in id order."""
        blocks, goals, start = scene.info["blocks"], [], 0
        for zone, size in zip(scene.info["zones"], scene.info["group_sizes"]):
            goals += stack_goals(scene, zone, blocks[start:start + size])
            start += size
        return goals

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        blocks, expected = scene.info["blocks"], scene.info["group_sizes"]
        stacks = P.zone_stacks(state, scene.info["zones"], blocks)
        diags: list[str] = []
        for s in stacks:
            z = label(state.spec(s.zone))
            if not s.members:
                diags.append(f"{z} holds no block")
            elif not s.ok:
                diags.append(f"the {len(s.members)} blocks in {z} are not one stack: {s.why}")
        placed = {i for s in stacks for i in s.members}
        diags += [f"{label(state.spec(i))} is in no zone" for i in blocks if i not in placed]
        sizes = sorted((len(s.members) for s in stacks), reverse=True)
        if sizes != expected:
            diags.append(f"the zones hold {sizes} blocks but the groups of {scene.info['k']} must be {expected}")
        ok = all(s.ok for s in stacks) and sizes == expected
        towers = sorted((len(s.tower) for s in stacks), reverse=True)
        met = sum(min(t, g) for t, g in zip(towers, expected))
        if ok:
            diags.append(f"{len(blocks)} blocks stacked in groups of {expected} in {len(stacks)} zones")
        return verdict(met, len(blocks), ok, diags)


TASK = DivideBlocks()
