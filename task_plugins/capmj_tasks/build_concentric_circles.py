"""Generated task 5: build-concentric-circles."""

from __future__ import annotations

import math

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Verdict
from capmj.tasks.spawn import Bounds, Spawner, pick_colors

from capmj_tasks.common import EXTENDED, BenchTask, shuffled, verdict
from capmj_tasks.structures import BLOCK, RING_GAP, Judgement, check_ring_blocks, colour_goal, ring_radius, ring_targets

ZONE_SCALE = 3.0
MAX_ZONE_YAW = 0.15
"""The 3× zone (0.36 m square) turns at most this much (rad) so that it fits the 0.5 m deep
workspace (its circumscribed circle, 0.51 m across, does not)."""
ZONE_REGION = Bounds(0.3, 0.7, -0.22, 0.22)
"""Where the zone centre may go: the outer ring then stays in the reachable part of the table."""
MIN_INNER_RADIUS = 0.06


def radii(n_inner: int, n_outer: int) -> tuple[float, float]:
    """The oracle's inner and outer radii (m): each ring keeps its own neighbours apart, and the
    rings keep ``RING_GAP`` between the inner ring's corners and the outer ring's inner faces."""
    r1 = ring_radius(n_inner, min_radius=MIN_INNER_RADIUS)
    r1_corner = math.hypot(r1 + BLOCK / 2, BLOCK / 2)
    return r1, ring_radius(n_outer, min_radius=r1_corner + RING_GAP + BLOCK / 2)


class BuildConcentricCircles(BenchTask):
    """Lay two colours of blocks out on two concentric circles in a triple-size zone.

    Task Description:
        "Construct two concentric circles in the zone using {n} {c1} and {n+4} {c2} blocks."  A
        3× zone (0.36 m square), n small c1 blocks and n + 4 small c2 blocks.

    Randomizations:
        n (4–6), the three colours (distinct), the zone's pose (yaw within ±0.15 rad so that it
        fits the workspace), spawn order, all block poses and yaws (collision-free, no block in
        the zone).

    Success Conditions:
        Every block upright on the table with its centre in the zone; the c1 centres within
        0.01 m of one least-squares circle and the c2 centres within 0.01 m of another
        (``predicates.concentric``), the two circle centres within 0.02 m of each other and the
        radii at least one block size (0.04 m) apart.  Either colour may be the inner circle.
        Progress: weighted share of these conditions.
    """

    name = "build-concentric-circles"
    tags = EXTENDED

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        zc, c1, c2 = pick_colors(rng, 3)
        n = int(rng.integers(4, 7))
        sp = Spawner(rng)
        zone = sp.zone(zc, scale=ZONE_SCALE, region=ZONE_REGION, yaw=float(rng.uniform(-MAX_ZONE_YAW, MAX_ZONE_YAW)))
        blocks = [sp.block(c, "small") for c in shuffled(rng, [c1] * n + [c2] * (n + 4))]
        return Scene(sp.objects, f"Construct two concentric circles in the zone using {n} {c1} and {n + 4} {c2} blocks.",
                     {"zone": zone.obj_id, "colors": [c1, c2], "blocks": [b.obj_id for b in blocks]})

    def _rings(self, scene: Scene) -> tuple[list[int], list[int]]:
        c1, c2 = scene.info["colors"]
        ids = scene.info["blocks"]
        return [i for i in ids if scene.by_id(i).color == c1], [i for i in ids if scene.by_id(i).color == c2]

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        """The n c1 blocks on the inner ring, then the n + 4 c2 blocks on the outer ring, both
        centred on the zone."""
        zone = scene.by_id(scene.info["zone"])
        inner, outer = self._rings(scene)
        r1, r2 = radii(len(inner), len(outer))
        goals = []
        for ids, r in ((inner, r1), (outer, r2)):
            col = scene.by_id(ids[0]).color
            goals.append(colour_goal(scene, ids, ring_targets(zone.pos, r, len(ids), zone.yaw), [col] * len(ids)))
        return goals

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        inner, outer = self._rings(scene)
        j = Judgement()
        check_ring_blocks(state, inner + outer, scene.info["zone"], j)
        ok, why = P.concentric(state, inner, outer, P.CENTRE_TOL, BLOCK, P.CIRCLE_TOL)
        j.check(ok, f"not two concentric circles: {why}", 4.0)
        if j.ok:
            j.diagnostics.append(why)
        return verdict(j.met, j.total, j.ok, j.diagnostics)


TASK = BuildConcentricCircles()
