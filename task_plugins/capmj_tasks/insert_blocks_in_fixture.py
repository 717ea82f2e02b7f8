"""Generated task 10: insert-blocks-in-fixture."""

from __future__ import annotations

import math

import numpy as np

from capmj.sim.objects import ObjectSpec, resting_z
from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Target, Verdict
from capmj.tasks.spawn import DEFAULT_COLORS, Spawner, pick_color, pick_colors
from capmj_tasks.common import EXTENDED, BenchTask, label, shuffled, verdict

SLOT_NAMES = ("(0,0,0)", "(a,0,0)", "(0,a,0)")

GOAL = ("Each L-shaped fixture can hold three blocks, suppose the block size is (a,a,a), then in fixture's local "
        "coordinate system, the three places that can hold blocks are [(0,0,0),(a,0,0),(0,a,0)]. Fill in all the "
        "fixtures which have random position and rotation with blocks, and make sure in the end in every fixture "
        "there are three blocks with different colors.")


def fill_plan(colours: list[str], n_fixtures: int) -> list[list[int]]:
    """Indices of ``colours`` per fixture (three each, distinct colours), or raise ValueError.

    Sorting by colour and dealing round robin works whenever no colour has more than
    ``n_fixtures`` blocks: a colour's run of ≤ n_fixtures consecutive indices hits every fixture
    at most once.
    """
    order = sorted(range(len(colours)), key=lambda i: (colours[i], i))
    plan = [[order[j] for j in range(f, len(order), n_fixtures)] for f in range(n_fixtures)]
    if any(len({colours[i] for i in p}) != 3 for p in plan):
        raise ValueError("no fill with three distinct colours per fixture")
    return plan


class InsertBlocksInFixture(BenchTask):
    """Fill every slot of every L-fixture with a block, three colours per fixture.

    Task Description:
        The goal text is fixed (see ``GOAL``): each L-shaped fixture holds three blocks of size a
        at (0,0,0), (a,0,0), (0,a,0) of its local frame (origin = the reported fixture position,
        x along the long wall); fill all fixtures so each holds three differently coloured
        blocks.  2–4 fixed fixtures of one colour and exactly three small blocks per fixture;
        no colour has more blocks than there are fixtures (so a valid fill exists), but colours
        repeat, so a careless fill can put two blocks of one colour into a fixture.
    Randomizations:
        Number of fixtures (2–4), their positions and yaws, the number of block colours (3 …),
        how many blocks each colour has (1 … number of fixtures), the colours, spawn order, all
        block poses and yaws.
    Success Conditions:
        Every slot of every fixture holds an upright block whose centre is within 0.012 m (3-D)
        of the slot centre in the world (``predicates.slot_occupants``) and each fixture's three
        blocks have three different colours.  Progress = (filled slots + 1 per fixture whose
        three blocks differ in colour) / (4 × fixtures).
    """

    name = "insert-blocks-in-fixture"
    tags = EXTENDED

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        nf = int(rng.integers(2, 5))
        n = 3 * nf
        k = int(rng.integers(3, min(n, 6) + 1))
        counts = [1] * k
        for _ in range(n - k):
            free = [c for c in range(k) if counts[c] < nf]
            counts[free[int(rng.integers(0, len(free)))]] += 1
        palette = pick_colors(rng, k)
        colours = shuffled(rng, [c for c, m in zip(palette, counts) for _ in range(m)])
        fixture_colour = pick_color(rng, DEFAULT_COLORS, exclude=palette)
        sp = Spawner(rng)
        fixtures = []
        for _ in range(nf):
            x, y = sp.sample_xy(P.FIXTURE_RADIUS)
            spec = ObjectSpec(sp.next_id, "fixture", fixture_colour, (x, y, resting_z("fixture")),
                              float(rng.uniform(0.0, 2 * math.pi)))
            fixtures.append(sp.add(spec, P.FIXTURE_RADIUS))
        blocks = [sp.block(c, "small") for c in colours]
        plan = fill_plan(colours, nf)
        return Scene(sp.objects, GOAL, {
            "fixtures": [f.obj_id for f in fixtures], "blocks": [b.obj_id for b in blocks],
            "fill": [[blocks[i].obj_id for i in p] for p in plan]})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        """Slot (0,0,0) of every fixture first, then (a,0,0), then (0,a,0), with the blocks of
        ``info["fill"]``, at the stated slots turned like the fixture (its walls keep
        ``FIXTURE_CLEARANCE`` from the slots, so exact targets land)."""
        goals = []
        for s in range(3):
            for fid, fill in zip(scene.info["fixtures"], scene.info["fill"]):
                f = scene.by_id(fid)
                x, y, z = P.fixture_slots(f.pos, f.yaw)[s]
                goals.append(OracleGoal((fill[s],), (Target((float(x), float(y), float(z)), f.yaw),), ((1,),),
                                        rotations=True, metric="pose", tolerance=P.PLANE_TOL))
        return goals

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        blocks = scene.info["blocks"]
        met = 0
        diags: list[str] = []
        for fid in scene.info["fixtures"]:
            fl = label(state.spec(fid))
            occ = P.slot_occupants(state, fid, blocks)
            slots = P.fixture_slots(state.pos(fid), state.poses[fid].yaw)
            for name, o, c in zip(SLOT_NAMES, occ, slots):
                if o is not None:
                    met += 1
                    continue
                d, near = min((float(np.linalg.norm(state.pos(i) - c)), i) for i in blocks)
                diags.append(f"slot {name} of {fl} is empty (nearest: {label(state.spec(near))}, {d:.3f} m from "
                             f"the slot centre, max {P.SLOT_TOL})")
            cols = [state.spec(o).color for o in occ if o is not None]
            if len(cols) == 3 and len(set(cols)) == 3:
                met += 1
            for c in sorted({c for c in cols if cols.count(c) > 1}):
                same = [str(o) for o in occ if o is not None and state.spec(o).color == c]
                diags.append(f"{fl} holds {len(same)} {c} blocks ({', '.join(same)}); its three must differ in colour")
        total = 4 * len(scene.info["fixtures"])
        ok = met == total
        if ok:
            diags.append(f"all {len(scene.info['fixtures'])} fixtures hold three blocks of three colours")
        return verdict(met, total, ok, diags)


TASK = InsertBlocksInFixture()
