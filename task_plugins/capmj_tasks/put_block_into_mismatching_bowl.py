"""Task I: put-block-into-mismatching-bowl."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Resample, Scene, Verdict
from capmj.tasks.spawn import Spawner, pick_colors

from capmj_tasks.common import BenchTask, label, shuffled, verdict
from capmj_tasks.put_block_into_matching_bowl import bowl_target, bowls_holding


def mismatch_assignment(blocks, bowls, order) -> list[tuple[int, int]] | None:
    """One-to-one block → bowl pairs with different colours (bowls tried in ``order``), or None."""
    out: list[tuple[int, int]] = []
    used: set[int] = set()

    def go(i: int) -> bool:
        if i == len(blocks):
            return True
        for j in order:
            if j not in used and bowls[j].color != blocks[i].color:
                used.add(j)
                out.append((blocks[i].obj_id, bowls[j].obj_id))
                if go(i + 1):
                    return True
                used.discard(j)
                out.pop()
        return False

    return out if go(0) else None


class PutBlockIntoMismatchingBowl(BenchTask):
    """Put each block into a bowl of a different colour.

    Task Description:
        "Put the blocks in the bowls with mismatching colors."  As task H (2–3 bowls of distinct
        colours, 2 … (number of bowls) small blocks coloured like different bowls, one distractor
        block or bowl of an unused colour) plus 0–2 further distractor bowls (≤ 3 in all).

    Randomizations:
        As task H, plus the number of extra distractor bowls.  Scenes with more blocks than
        bowls are resampled, so a one-to-one mismatching assignment always exists; the oracle's
        assignment is drawn at random among the bowls.

    Success Conditions:
        Every block (distractor blocks included) is in a bowl of a different colour
        (``predicates.in_bowl``: centre within 0.05 m of the bowl centre in xy and below the rim).
        Sharing a bowl is allowed by the predicate; the oracle uses one bowl per block.  Progress =
        blocks in a mismatching bowl / blocks.
    """

    name = "put-block-into-mismatching-bowl"

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        k = int(rng.integers(2, 4))
        m = int(rng.integers(2, k + 1))
        distractor_block = bool(rng.integers(0, 2))
        n_extra = int(rng.integers(0, 3))
        n_dbowls = n_extra + (0 if distractor_block else 1)
        if m + int(distractor_block) > k + n_dbowls:
            raise Resample("more blocks than bowls")
        cols = pick_colors(rng, k + int(distractor_block) + n_dbowls)
        bowl_cols = cols[:k]
        db_col = cols[k:k + int(distractor_block)]
        dbowl_cols = cols[k + int(distractor_block):]
        block_cols = [bowl_cols[int(i)] for i in rng.choice(k, size=m, replace=False)] + db_col
        sp = Spawner(rng)
        bowls = [sp.bowl(c) for c in shuffled(rng, bowl_cols + dbowl_cols)]
        blocks = [sp.block(c, "small") for c in shuffled(rng, block_cols)]
        assignment = mismatch_assignment(blocks, bowls, [int(j) for j in rng.permutation(len(bowls))])
        if assignment is None:  # pragma: no cover - impossible when blocks <= bowls (Hall)
            raise Resample("no mismatching assignment")
        return Scene(sp.objects, "Put the blocks in the bowls with mismatching colors.", {
            "blocks": [b.obj_id for b in blocks], "bowls": [w.obj_id for w in bowls],
            "assignment": [list(p) for p in assignment],
            "distractor_blocks": [b.obj_id for b in blocks if b.color in db_col],
            "distractor_bowls": [w.obj_id for w in bowls if w.color in dbowl_cols],
        })

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        """One goal: every block to any bowl of another colour, one-to-one.  Targets are listed in
        the order of the stored assignment (then the unused bowls), so first-fit and optimal
        assignment both succeed."""
        pairs = [tuple(p) for p in scene.info["assignment"]]
        used = {w for _, w in pairs}
        bowl_ids = [w for _, w in pairs] + [w for w in scene.info["bowls"] if w not in used]
        objs = [scene.by_id(b) for b, _ in pairs]
        bowls = [scene.by_id(w) for w in bowl_ids]
        # target j holds the height of the block assigned to it (all blocks are small).
        targets = tuple(bowl_target(w, objs[0]) for w in bowls)
        matches = tuple(tuple(int(o.color != w.color) for w in bowls) for o in objs)
        return [OracleGoal(tuple(o.obj_id for o in objs), targets, matches, metric="pose", tolerance=P.BOWL_TOL)]

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        met, diags = 0, []
        bowls = scene.info["bowls"]
        for b in scene.info["blocks"]:
            s = state.spec(b)
            inside = bowls_holding(state, b, bowls)
            good = [w for w in inside if state.spec(w).color != s.color]
            if good:
                met += 1
            elif inside:
                diags.append(f"{label(s)} is in the {label(state.spec(inside[0]))}, which has the same colour")
            else:
                diags.append(f"{label(s)} is in no bowl")
        n = len(scene.info["blocks"])
        ok = met == n
        if ok:
            diags.append("every block is in a bowl of a different colour")
        return verdict(met, n, ok, diags)


TASK = PutBlockIntoMismatchingBowl()
