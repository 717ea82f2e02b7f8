"""Generated task 4: construct-circle-ball-middle."""

from __future__ import annotations

import numpy as np

from capmj.tasks.protocol import Scene
from capmj.tasks.spawn import SPAWN_BOUNDS, Bounds, Spawner, pick_colors

from capmj_tasks.common import shuffled
from capmj_tasks.construct_circle_with_blocks import CircleTask
from capmj_tasks.structures import BLOCK, ring_radius

PER_COLOUR = 4
RING_MIN_RADIUS = 0.08
"""Smallest ring radius (m) of the oracle: a block's inner face stays 3 cm from the 0.03 m ball."""


class ConstructCircleBallMiddle(CircleTask):
    """Lay blocks of two colours out on a circle around a fixed ball, colours alternating.

    Task Description:
        "Construct a circle with suitable radius with alternating {c1} and {c2} blocks around the
        ball."  One fixed ball (radius 0.03 m) and 4 small blocks of each of two colours.

    Randomizations:
        The three colours (distinct), spawn order, all poses and yaws.  The ball stands where a
        ring around it stays in the reachable workspace, and no block spawns within the ring's
        square around it.

    Success Conditions:
        Every block upright on the table; all centres within 0.01 m of the least-squares circle
        through them (``predicates.circle_of``) with radius at least 0.04 m; no two footprints
        touching (closer than 0.001 m); colours alternating in angular order around the fitted
        centre; that centre within 0.02 m of the ball's centre in xy.  Progress: weighted share
        of these conditions.
    """

    name = "construct-circle-ball-middle"

    def radius(self, n: int) -> float:
        return ring_radius(n, min_radius=RING_MIN_RADIUS)

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        bc, c1, c2 = pick_colors(rng, 3)
        reach = self.radius(2 * PER_COLOUR) + BLOCK
        sp = Spawner(rng)
        ball = sp.place("ball", bc, region=SPAWN_BOUNDS.shrink(reach - sp.area_margin))
        x, y = ball.pos[0], ball.pos[1]
        keep_free = Bounds(x - reach, x + reach, y - reach, y + reach)
        blocks = [sp.block(c, "small", avoid=[keep_free]) for c in shuffled(rng, [c1] * PER_COLOUR + [c2] * PER_COLOUR)]
        return Scene(sp.objects,
                     f"Construct a circle with suitable radius with alternating {c1} and {c2} blocks around the ball.",
                     {"ball": ball.obj_id, "colors": [c1, c2], "blocks": [b.obj_id for b in blocks]})


TASK = ConstructCircleBallMiddle()
