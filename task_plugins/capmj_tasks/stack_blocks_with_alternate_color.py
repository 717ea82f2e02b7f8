"""Task J: stack-blocks-with-alternate-color."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks.protocol import OracleGoal, Scene, Verdict
from capmj.tasks.spawn import Spawner, pick_colors

from capmj_tasks.common import BenchTask, check_stack, shuffled, stack_goals, verdict


class StackBlocksWithAlternateColor(BenchTask):
    """Stack blocks of two colours alternately in a zone, starting with a named colour.

    Task Description:
        "Stack blocks with alternate colors on the {c1} zone, starting with the {c2} color."  A
        target zone (c1), a distractor zone of another colour, and 2–5 small blocks of two
        colours (c2 and another), ceil(n/2) of colour c2 and floor(n/2) of the other, so the
        alternation from c2 uses every block.  Block colours differ from both zone colours.

    Randomizations:
        Number of blocks (2–5), the four colours (distinct), spawn order, all poses and yaws.

    Success Conditions:
        All blocks form one stack inside the target zone (``predicates.is_stack``) whose bottom
        block has colour c2 and whose colours alternate going up.  Progress = tallest valid
        alternating partial stack (bottom c2) in the zone / blocks.
    """

    name = "stack-blocks-with-alternate-color"

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        zc, dc, c2, c3 = pick_colors(rng, 4)
        sp = Spawner(rng)
        zone, dzone = sp.zone(zc), sp.zone(dc)
        n = int(rng.integers(2, 6))
        colours = [c2] * ((n + 1) // 2) + [c3] * (n // 2)
        blocks = [sp.block(c, "small") for c in shuffled(rng, colours)]
        return Scene(
            sp.objects,
            f"Stack blocks with alternate colors on the {zc} zone, starting with the {c2} color.",
            {"zone": zone.obj_id, "distractor_zones": [dzone.obj_id], "start_color": c2, "other_color": c3,
             "blocks": [b.obj_id for b in blocks]},
        )

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        c2, c3 = scene.info["start_color"], scene.info["other_color"]
        first = [i for i in scene.info["blocks"] if scene.by_id(i).color == c2]
        second = [i for i in scene.info["blocks"] if scene.by_id(i).color == c3]
        order = [x for pair in zip(first, second + [None]) for x in pair if x is not None]
        return stack_goals(scene, scene.info["zone"], order)

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        c2, c3 = scene.info["start_color"], scene.info["other_color"]
        ids = scene.info["blocks"]

        def accept(level: int, obj_id: int) -> bool:
            return state.spec(obj_id).color == (c2 if level % 2 == 0 else c3)

        rep = check_stack(state, ids, scene.info["zone"], accept=accept)
        diags = list(rep.diagnostics)
        if not rep.ok:
            seq = [state.spec(i).color for i in sorted(ids, key=lambda i: float(state.pos(i)[2]))]
            diags.append(f"colours bottom to top: {', '.join(seq)} (need {c2}, {c3}, {c2}, …)")
        return verdict(len(rep.tower), len(ids), rep.ok, diags)


TASK = StackBlocksWithAlternateColor()
