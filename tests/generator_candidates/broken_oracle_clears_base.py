# expect: runtime:oracle_solves
# goal: Put the small {color} block on the big {color2} block.
"""Put a small block on a big block (subtly broken: the oracle clears the unmoved base block off the target)."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Target, Verdict
from capmj.tasks.spawn import Spawner, pick_colors


class StackSmallBlockOnBigBlock:
    """Put the small block of one colour on the big block of another.

    Task Description:
        "Put the small {c2} block on the big {c1} block."  One big and one small block of distinct
        colours, plus one small distractor block of a third colour.

    Randomizations:
        Colours, all poses and yaws.

    Success Conditions:
        The small block rests on the big one (predicates.resting_on: axes within 0.02 m, heights
        within 0.015 m) and is not tilted.
    """

    name = "stack-small-block-on-big-block"
    tags = frozenset({"generated-by-llm"})

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        c1, c2, c3 = pick_colors(rng, 3)
        sp = Spawner(rng)
        big = sp.block(c1, "big")
        small = sp.block(c2, "small")
        sp.block(c3, "small")
        return Scene(sp.objects, f"Put the small {c2} block on the big {c1} block.",
                     {"big": big.obj_id, "small": small.obj_id})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        big, small = scene.by_id(scene.info["big"]), scene.by_id(scene.info["small"])
        t = Target((big.pos[0], big.pos[1], big.height + small.height / 2))
        return [OracleGoal((small.obj_id,), (t,), ((1,),), metric="pose", tolerance=P.PLANE_TOL)]

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        big, small = scene.info["big"], scene.info["small"]
        ok = P.resting_on(state, small, big) and not P.toppled(state, small)
        return Verdict(ok, 1.0 if ok else 0.0, ("the small block is on the big one" if ok else
                                                 "the small block is not resting on the big one",))


TASK = StackSmallBlockOnBigBlock()
