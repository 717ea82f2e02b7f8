"""Generated task 8: stack-most-color-block."""

from __future__ import annotations

import numpy as np

from capmj.tasks.protocol import Scene
from capmj.tasks.spawn import Spawner, pick_color, pick_colors
from capmj_tasks.common import EXTENDED, SelectedStackTask, shuffled

MAJORITY = (3, 6)
"""Size range of the majority colour: at most six small blocks (a 0.24 m tower) stay reachable."""


class StackMostColorBlock(SelectedStackTask):
    """Stack the blocks of the most frequent colour in the zone.

    Task Description:
        "Stack blocks of the same color that has the largest quantity in the zone."  10–15 small
        blocks of 3–5 colours, one colour strictly more frequent than every other, and one zone
        (its colour may equal a block colour; only the counts matter).
    Randomizations:
        Number of colours (3–5), the colours, the majority count (3–6) and the other counts (1 …
        majority − 1, total 10–15), zone colour, spawn order, all poses and yaws.
    Success Conditions:
        The majority-colour blocks form one stack inside the zone (``predicates.is_stack``) and
        no other block has its centre in the zone.  Progress = (blocks on the valid partial stack
        + 1 if the zone holds no other block) / (majority count + 1).
    """

    name = "stack-most-color-block"
    tags = EXTENDED

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        while True:
            k = int(rng.integers(3, 6))
            top = int(rng.integers(MAJORITY[0], MAJORITY[1] + 1))
            others = [int(v) for v in rng.integers(1, top, k - 1)]
            if 10 <= top + sum(others) <= 15:
                break
        colours = pick_colors(rng, k)
        sp = Spawner(rng)
        zone = sp.zone(pick_color(rng))
        plan = [c for c, n in zip(colours, [top] + others) for _ in range(n)]
        blocks = [sp.block(c, "small") for c in shuffled(rng, plan)]
        selected = [b.obj_id for b in blocks if b.color == colours[0]]
        return Scene(sp.objects, "Stack blocks of the same color that has the largest quantity in the zone.",
                     {"zone": zone.obj_id, "color": colours[0], "selected": selected,
                      "blocks": [b.obj_id for b in blocks]})


TASK = StackMostColorBlock()
