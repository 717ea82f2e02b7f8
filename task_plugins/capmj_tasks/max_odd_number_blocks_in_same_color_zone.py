"""Generated task 7: max-odd-number-blocks-in-same-color-zone."""

from __future__ import annotations

import math

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Target, Verdict
from capmj.tasks.spawn import Spawner, pick_colors
from capmj_tasks.common import EXTENDED, BenchTask, label, shuffled, verdict

MAX_PER_COLOR = 6
"""At most this many blocks per colour, so a zone takes at most 5 (its spot grid below)."""
SPOTS = tuple((u, v) for v in (0.0, -0.05, 0.05) for u in (-0.025, 0.025))
"""Oracle spots in the zone frame (m): a 2 × 3 grid at 0.05 m pitch, centres 0.01 m inside the
0.12 m zone, 0.01 m of air between blocks lined up with the zone."""


class MaxOddNumberBlocksInSameColorZone(BenchTask):
    """Put the largest odd number of each colour's blocks into that colour's zone.

    Task Description:
        "Place the maximal odd number of blocks of the same color in each correspondingly colored
        zone."  7–14 small blocks of three colours, 1–6 of each, and one zone per colour.  A colour
        with c blocks must have the largest odd number ≤ c of them in its zone (c − 1 when c is
        even, so one block stays out).
    Randomizations:
        The three colours, the count of each (1–6, total 7–14, at least one even count so "odd"
        matters), spawn order, all poses and yaws (no block starts in a zone).
    Success Conditions:
        Every zone holds exactly ``largest_odd_at_most(c)`` blocks of its colour (centre in the
        zone, ``predicates.in_zone``) and no block of another colour.  Progress = Σ over zones of
        min(own blocks in it, target) + 1 when it holds no excess or foreign block, over Σ
        (target + 1).
    """

    name = "max-odd-number-blocks-in-same-color-zone"
    tags = EXTENDED

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        while True:
            counts = [int(v) for v in rng.integers(1, MAX_PER_COLOR + 1, 3)]
            if 7 <= sum(counts) <= 14 and any(c % 2 == 0 for c in counts):
                break
        colours = pick_colors(rng, 3)
        sp = Spawner(rng)
        zones = [sp.zone(c) for c in colours]
        blocks = [sp.block(c, "small") for c in shuffled(rng, [c for c, n in zip(colours, counts) for _ in range(n)])]
        targets = {z.color: P.largest_odd_at_most(n) for z, n in zip(zones, counts)}
        return Scene(sp.objects,
                     "Place the maximal odd number of blocks of the same color in each correspondingly colored zone.",
                     {"zones": [z.obj_id for z in zones], "blocks": [b.obj_id for b in blocks], "targets": targets})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        """Per zone: the target number of its colour's blocks (those spawned nearest the zone) to
        the zone's spots, lined up with the zone."""
        goals = []
        for zid in scene.info["zones"]:
            z = scene.by_id(zid)
            m = scene.info["targets"][z.color]
            own = sorted((b for b in map(scene.by_id, scene.info["blocks"]) if b.color == z.color),
                         key=lambda b: (math.dist(b.pos[:2], z.pos[:2]), b.obj_id))[:m]
            cs, sn = math.cos(z.yaw), math.sin(z.yaw)
            targets = tuple(Target((z.pos[0] + cs * u - sn * v, z.pos[1] + sn * u + cs * v, b.height / 2), z.yaw)
                            for (u, v), b in zip(SPOTS, own))
            goals.append(OracleGoal(tuple(b.obj_id for b in own), targets, tuple((1,) * m for _ in own),
                                    metric="pose", tolerance=P.PLANE_TOL))
        return goals

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        met = total = 0
        ok = True
        diags: list[str] = []
        for zid in scene.info["zones"]:
            z = state.spec(zid)
            target = scene.info["targets"][z.color]
            have = P.zone_color_counts(state, zid)
            own = len(have.get(z.color, []))
            foreign = [i for c, ids in have.items() if c != z.color for i in ids]
            clean = own <= target and not foreign
            met += min(own, target) + clean
            total += target + 1
            if own != target:
                ok = False
                n = sum(1 for i in scene.info["blocks"] if state.spec(i).color == z.color)
                diags.append(f"{label(z)} holds {own} {z.color} block(s), needs exactly {target} "
                             f"(the largest odd number ≤ {n} {z.color} blocks)")
            if foreign:
                ok = False
                diags += [f"{label(state.spec(i))} must not be in the {label(z)}" for i in foreign]
        if ok:
            diags.append("every zone holds the largest odd number of its colour's blocks and nothing else")
        return verdict(met, total, ok, diags)


TASK = MaxOddNumberBlocksInSameColorZone()
