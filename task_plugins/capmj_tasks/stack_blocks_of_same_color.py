"""Task C: stack-blocks-of-same-color."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks.protocol import OracleGoal, Scene, Verdict
from capmj.tasks.spawn import Spawner, pick_colors

from capmj_tasks.common import BenchTask, check_stack, exclusive_zone, shuffled, stack_goals, verdict


class StackBlocksOfSameColor(BenchTask):
    """Stack the blocks of each colour that has a zone in that colour's zone.

    Task Description:
        "Stack all the blocks of the same color together in the same colored zone."  1–3
        colours, each with 2–3 small blocks and one zone of that colour; 0–1 distractor zone of a
        colour no block has; 0–2 distractor blocks of colours without a zone.

    Randomizations:
        Number of colours (1–3), blocks per colour (2–3), colours, presence of the distractor
        zone, number of distractor blocks (0–2, distinct colours), spawn order of the blocks,
        all poses and yaws.

    Success Conditions:
        For every colour with a zone: all blocks of that colour form one stack inside that zone
        (``predicates.is_stack``); no distractor block has its centre inside a target zone.
        Progress = blocks on valid partial stacks + one unit per target zone free of
        distractors, over the number of units.
    """

    name = "stack-blocks-of-same-color"

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        sp = Spawner(rng)
        k = int(rng.integers(1, 4))
        has_dz = bool(rng.integers(0, 2))
        nd = int(rng.integers(0, 3))
        cols = pick_colors(rng, k + int(has_dz) + nd)
        group_cols, dz_col, db_cols = cols[:k], cols[k:k + int(has_dz)], cols[k + int(has_dz):]
        zones = [sp.zone(c) for c in group_cols]
        dzones = [sp.zone(c) for c in dz_col]
        colours = [c for c in group_cols for _ in range(int(rng.integers(2, 4)))] + list(db_cols)
        blocks = [sp.block(c, "small") for c in shuffled(rng, colours)]
        groups = [{"color": z.color, "zone": z.obj_id, "blocks": [b.obj_id for b in blocks if b.color == z.color]}
                  for z in zones]
        return Scene(
            sp.objects,
            "Stack all the blocks of the same color together in the same colored zone.",
            {"groups": groups, "distractor_zones": [z.obj_id for z in dzones],
             "distractor_blocks": [b.obj_id for b in blocks if b.color in db_cols]},
        )

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        goals: list[OracleGoal] = []
        for g in scene.info["groups"]:
            goals += stack_goals(scene, g["zone"], g["blocks"])
        return goals

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        met = total = 0
        ok = True
        diags: list[str] = []
        dist = scene.info["distractor_blocks"]
        for g in scene.info["groups"]:
            rep = check_stack(state, g["blocks"], g["zone"], what=f"{g['color']} blocks")
            clean, extra = exclusive_zone(state, g["zone"], allowed=[i for i in state.poses if i not in dist])
            met += len(rep.tower) + clean
            total += len(g["blocks"]) + 1
            ok = ok and rep.ok and clean
            diags += rep.diagnostics + extra
        return verdict(met, total, ok, diags)


TASK = StackBlocksOfSameColor()
