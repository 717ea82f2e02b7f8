# expect: accepted
# goal: Put the {color} block in the {color2} bowl.
"""One named block into one named bowl among distractors (a hand-written good candidate)."""

from __future__ import annotations

import numpy as np

from capmj.sim.objects import BOWL_FLOOR, BOWL_HEIGHT
from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Target, Verdict
from capmj.tasks.spawn import Spawner, pick_colors


class PutNamedBlockInNamedBowl:
    """Put one named block into one named bowl.

    Task Description:
        "Put the {c1} block in the {c2} bowl."  Two bowls and three small blocks, all colours
        distinct.

    Randomizations:
        Colours, which bowl and block are named, all poses and yaws.

    Success Conditions:
        The named block is in the named bowl (predicates.in_bowl) and no other block is in a bowl.
    """

    name = "put-named-block-in-named-bowl"
    tags = frozenset({"generated-by-llm"})

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        cols = pick_colors(rng, 5)
        sp = Spawner(rng)
        bowls = [sp.bowl(c) for c in cols[:2]]
        blocks = [sp.block(c, "small") for c in cols[2:]]
        w, b = bowls[int(rng.integers(0, 2))], blocks[int(rng.integers(0, 3))]
        return Scene(sp.objects, f"Put the {b.color} block in the {w.color} bowl.",
                     {"block": b.obj_id, "bowl": w.obj_id, "bowls": [x.obj_id for x in bowls],
                      "others": [x.obj_id for x in blocks if x is not b]})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        w, b = scene.by_id(scene.info["bowl"]), scene.by_id(scene.info["block"])
        z = w.pos[2] - BOWL_HEIGHT / 2 + BOWL_FLOOR + b.height / 2
        return [OracleGoal((b.obj_id,), (Target((w.pos[0], w.pos[1], z)),), ((1,),), tolerance=P.BOWL_TOL)]

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        inside = P.in_bowl(state, scene.info["block"], scene.info["bowl"])
        strays = [o for o in scene.info["others"] if any(P.in_bowl(state, o, w) for w in scene.info["bowls"])]
        ok = inside and not strays
        diags = [] if inside else ["the named block is not in the named bowl"]
        diags += [f"block {o} must not be in a bowl" for o in strays]
        return Verdict(ok, 1.0 if ok else 0.5 * inside, tuple(diags) or ("done",))


TASK = PutNamedBlockInNamedBowl()
