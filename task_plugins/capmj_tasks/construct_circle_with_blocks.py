"""Generated task 3: construct-circle-with-blocks (and the shared code of task 4)."""

from __future__ import annotations

import math

import numpy as np

from capmj.sim.objects import BLOCK_SIZES
from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Verdict
from capmj.tasks.spawn import Spawner, pick_colors

from capmj_tasks.common import EXTENDED, BenchTask, label, shuffled, verdict
from capmj_tasks.structures import Judgement, check_ring_blocks, colour_goal, ring_radius, ring_targets

MIN_RADIUS = BLOCK_SIZES["small"]
"""A circle must have a radius of at least one block size (m)."""


class CircleTask(BenchTask):
    """Shared goals and verdict of tasks 3 and 4: alternating colours on one circle.

    ``scene.info`` holds ``blocks``, ``colors`` (the two colours, first named first), and either
    ``zone`` (task 3) or ``ball`` (task 4), the object the circle must lie in or go around.
    """

    tags = EXTENDED

    def centre_of(self, scene: Scene) -> tuple[float, float]:
        obj = scene.by_id(scene.info["zone"] if "zone" in scene.info else scene.info["ball"])
        return obj.pos[0], obj.pos[1]

    def radius(self, n: int) -> float:
        return ring_radius(n, min_radius=MIN_RADIUS)

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        """One goal: 2n targets evenly on the ring, colours alternating, each block to a target of
        its colour."""
        ids = list(scene.info["blocks"])
        c1, c2 = scene.info["colors"]
        targets = ring_targets(self.centre_of(scene), self.radius(len(ids)), len(ids))
        return [colour_goal(scene, ids, targets, [c1 if k % 2 == 0 else c2 for k in range(len(ids))])]

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        """Blocks on the table weigh 1 together; the circle 2, no touching 1, alternation 2, the
        ball as centre 2 — the last three only count once the circle exists."""
        ids = list(scene.info["blocks"])
        ball = scene.info.get("ball")
        j = Judgement()
        blocks = Judgement()
        on_table = check_ring_blocks(state, ids, scene.info.get("zone"), blocks)
        j.partial(blocks.met / blocks.total, 1.0)
        j.diagnostics += blocks.diagnostics
        ok, centre, radius, why = P.circle_of(state, ids, P.CIRCLE_TOL, MIN_RADIUS)
        j.check(ok, f"the blocks are not on one circle: {why}", 2.0)
        touching = P.touching_pairs(state, on_table)
        j.check(ok and not touching, "; ".join(f"{label(state.spec(a))} touches {label(state.spec(b))}"
                                               for a, b, _ in touching[:3]))
        alt, why = P.alternates(state, ids, centre) if math.isfinite(radius) else (False, "")
        j.check(ok and alt, f"colours do not alternate around the circle: {why}" if why and not alt else "", 2.0)
        if ball is not None:
            d = float(np.hypot(*(centre - state.pos(ball)[:2])))
            j.check(ok and d <= P.CENTRE_TOL, f"the circle's centre is {d:.3f} m from the {label(state.spec(ball))} "
                    f"(max {P.CENTRE_TOL})" if d > P.CENTRE_TOL and math.isfinite(radius) else "", 2.0)
        if j.ok:
            j.diagnostics.append(f"{len(ids)} blocks on a circle of radius {radius:.3f} m, colours alternating")
        return verdict(j.met, j.total, j.ok, j.diagnostics)


class ConstructCircleWithBlocks(CircleTask):
    """Lay blocks of two colours out on a circle in a large zone, colours alternating.

    Task Description:
        "Construct a circle with suitable radius with alternating {c1} and {c2} blocks in the
        zone."  A 2.2× zone (0.264 m square) and 4–6 small blocks of each of two colours.

    Randomizations:
        The number of blocks per colour (4–6, the same for both), the three colours (distinct),
        spawn order, all poses and yaws (collision-free, no block in the zone).

    Success Conditions:
        Every block upright on the table with its centre in the zone; all centres within 0.01 m
        of the least-squares circle through them (``predicates.circle_of``), whose radius is at
        least one block size (0.04 m); no two footprints touching (``predicates.touching_pairs``,
        closer than 0.001 m); colours alternating in angular order around the fitted centre
        (``predicates.alternates``).  Progress: weighted share of these conditions.
    """

    name = "construct-circle-with-blocks"

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        zc, c1, c2 = pick_colors(rng, 3)
        n = int(rng.integers(4, 7))
        sp = Spawner(rng)
        zone = sp.zone(zc, scale=2.2)
        blocks = [sp.block(c, "small") for c in shuffled(rng, [c1] * n + [c2] * n)]
        return Scene(sp.objects,
                     f"Construct a circle with suitable radius with alternating {c1} and {c2} blocks in the zone.",
                     {"zone": zone.obj_id, "colors": [c1, c2], "blocks": [b.obj_id for b in blocks]})


TASK = ConstructCircleWithBlocks()
