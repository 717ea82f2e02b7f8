"""Task H: put-block-into-matching-bowl."""

from __future__ import annotations

import math

import numpy as np

from capmj.sim.objects import BOWL_FLOOR, BOWL_HEIGHT, ObjectSpec
from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Target, Verdict
from capmj.tasks.spawn import Spawner, pick_colors

from capmj_tasks.common import BenchTask, label, shuffled, verdict


def bowl_target(bowl: ObjectSpec, block: ObjectSpec) -> Target:
    """Centre target of a block resting on a bowl's floor, at the bowl centre."""
    floor_top = bowl.pos[2] - BOWL_HEIGHT / 2 + BOWL_FLOOR
    return Target((float(bowl.pos[0]), float(bowl.pos[1]), float(floor_top + block.height / 2)), None)


def where_bowl(state: SceneState, block: int, bowl: int) -> str:
    """Why ``block`` is not in ``bowl`` (distance or height)."""
    p, b = state.pos(block), state.pos(bowl)
    d = math.hypot(p[0] - b[0], p[1] - b[1])
    if d > P.BOWL_TOL:
        return f"{d:.3f} m from its centre (max {P.BOWL_TOL})"
    return f"above the rim (z = {p[2]:.3f} m)"


def bowls_holding(state: SceneState, block: int, bowls) -> list[int]:
    return [w for w in bowls if P.in_bowl(state, block, w)]


class PutBlockIntoMatchingBowl(BenchTask):
    """Put each block into the bowl of its colour.

    Task Description:
        "Put the blocks in the bowls with matching colors."  2–3 bowls of distinct colours,
        2 … (number of bowls) small blocks each coloured like a different bowl, and one distractor:
        either a block or a bowl of a colour nothing else has.

    Randomizations:
        Number of bowls (2–3), number of matching blocks, colours, which bowls get a block,
        whether the distractor is a block or a bowl, spawn order, all poses and yaws.  Each bowl
        receives at most one block, so the oracle places every block at its bowl's centre.

    Success Conditions:
        Every block with a same-coloured bowl is in that bowl (``predicates.in_bowl``: centre
        within 0.05 m of the bowl centre in xy and below the rim) and the distractor block (if
        any) is in no bowl.  Progress = blocks meeting their condition / blocks.
    """

    name = "put-block-into-matching-bowl"

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        k = int(rng.integers(2, 4))
        m = int(rng.integers(2, k + 1))
        distractor_block = bool(rng.integers(0, 2))
        cols = pick_colors(rng, k + 1)
        bowl_cols, extra = cols[:k], cols[k]
        block_cols = [bowl_cols[int(i)] for i in rng.choice(k, size=m, replace=False)]
        sp = Spawner(rng)
        bowl_plan = bowl_cols + ([] if distractor_block else [extra])
        bowls = [sp.bowl(c) for c in shuffled(rng, bowl_plan)]
        block_plan = block_cols + ([extra] if distractor_block else [])
        blocks = [sp.block(c, "small") for c in shuffled(rng, block_plan)]
        by_col = {w.color: w.obj_id for w in bowls}
        pairs = [[b.obj_id, by_col[b.color]] for b in blocks if b.color in by_col]
        return Scene(sp.objects, "Put the blocks in the bowls with matching colors.", {
            "pairs": pairs, "bowls": [w.obj_id for w in bowls], "blocks": [b.obj_id for b in blocks],
            "distractor_blocks": [b.obj_id for b in blocks if b.color not in by_col],
            "distractor_bowls": [w.obj_id for w in bowls if w.color not in block_cols],
        })

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        pairs = scene.info["pairs"]
        targets = tuple(bowl_target(scene.by_id(w), scene.by_id(b)) for b, w in pairs)
        matches = tuple(tuple(int(i == j) for j in range(len(pairs))) for i in range(len(pairs)))
        return [OracleGoal(tuple(b for b, _ in pairs), targets, matches, metric="pose", tolerance=P.BOWL_TOL)]

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        met, diags = 0, []
        bowls = scene.info["bowls"]
        for b, w in scene.info["pairs"]:
            if P.in_bowl(state, b, w):
                met += 1
            else:
                diags.append(f"{label(state.spec(b))} is not in the {label(state.spec(w))}: {where_bowl(state, b, w)}")
        for b in scene.info["distractor_blocks"]:
            inside = bowls_holding(state, b, bowls)
            if inside:
                diags.append(f"{label(state.spec(b))} has no matching bowl but is in the {label(state.spec(inside[0]))}")
            else:
                met += 1
        n = len(scene.info["pairs"]) + len(scene.info["distractor_blocks"])
        ok = met == n
        if ok:
            diags.append("every block with a matching bowl is in it; no distractor block in a bowl")
        return verdict(met, n, ok, diags)


TASK = PutBlockIntoMatchingBowl()
