# expect: accepted
# goal: Stack the small {color} block on the big {color2} block in the {zone} zone.
"""A two-level stack in a zone (a hand-written good candidate)."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Target, Verdict
from capmj.tasks.spawn import Spawner, pick_colors


class StackSmallOnBigInZone:
    """Build a two-block tower, big block at the bottom, inside a zone.

    Task Description:
        "Stack the small {c2} block on the big {c1} block in the {z} zone."  One zone, one big and
        one small block, one distractor block.

    Randomizations:
        Colours (all distinct), all poses and yaws.

    Success Conditions:
        predicates.is_stack([big, small]) and both centres inside the zone.
    """

    name = "stack-small-on-big-in-zone"
    tags = frozenset({"generated-by-llm"})

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        z, c1, c2, c3 = pick_colors(rng, 4)
        sp = Spawner(rng)
        zone = sp.zone(z)
        big = sp.block(c1, "big")
        small = sp.block(c2, "small")
        sp.block(c3, "small")
        goal = f"Stack the small {c2} block on the big {c1} block in the {z} zone."
        return Scene(sp.objects, goal, {"zone": zone.obj_id, "order": [big.obj_id, small.obj_id]})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        zone = scene.by_id(scene.info["zone"])
        goals, h = [], 0.0
        for i in scene.info["order"]:
            b = scene.by_id(i)
            goals.append(OracleGoal((i,), (Target((zone.pos[0], zone.pos[1], h + b.height / 2)),), ((1,),),
                                    tolerance=P.PLANE_TOL))
            h += b.height
        return goals

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        order, zone = scene.info["order"], scene.info["zone"]
        stacked, why = P.is_stack(state, order)
        inside = all(P.in_zone(state, i, zone) for i in order)
        ok = stacked and inside
        met = int(stacked) + int(inside)
        return Verdict(ok, 1.0 if ok else met / 2 * 0.99, ("stacked in the zone",) if ok else (why or "not in the zone",))


TASK = StackSmallOnBigInZone()
