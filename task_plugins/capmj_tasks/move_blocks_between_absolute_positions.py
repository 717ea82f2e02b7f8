"""Task F: move-blocks-between-absolute-positions (and the shared code of task G)."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Resample, Scene, Target, Verdict
from capmj.tasks.spawn import Spawner, free_positions, pick_colors

from capmj_tasks.common import BenchTask, label, shuffled, start_positions, verdict

SIZE_WORD = {"big": "bigger", "small": "smaller"}


class AreaMoveTask(BenchTask):
    """Shared scene, oracle and check of tasks F and G (``by_size`` selects G's variant)."""

    by_size = False

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        q = P.QUADRANTS
        i1, i2 = (int(v) for v in rng.choice(len(q), size=2, replace=False))
        area1, area2 = q[i1], q[i2]
        n1 = int(rng.integers(3, 5))
        size = ("big", "small")[int(rng.integers(0, 2))]
        if self.by_size:
            other = "small" if size == "big" else "big"
            n_sel = int(rng.integers(1, n1))
            in1 = [size] * n_sel + [other] * (n1 - n_sel)
        else:
            in1 = [("big", "small")[int(v)] for v in rng.integers(0, 2, n1)]
        n_out = int(rng.integers(1, 4))
        out = [("big", "small")[int(v)] for v in rng.integers(0, 2, n_out)]
        plan = shuffled(rng, [(s, True) for s in in1] + [(s, False) for s in out])
        colours = pick_colors(rng, len(plan))
        sp = Spawner(rng)
        blocks = []
        for (s, inside), c in zip(plan, colours):
            if inside:
                blocks.append(sp.block(c, s, region=area1))
            else:
                blocks.append(sp.block(c, s, avoid=(area1, area2)))
        in_area1 = [b.obj_id for (_, inside), b in zip(plan, blocks) if inside]
        size_of = {b.obj_id: b.size for b in blocks}
        selected = [i for i in in_area1 if not self.by_size or size_of[i] == size]
        if not selected:
            raise Resample("nothing to move")
        info = {"area1": area1, "area2": area2, "selected": selected, "in_area1": in_area1,
                "blocks": [b.obj_id for b in blocks], "start_positions": start_positions(blocks)}
        if self.by_size:
            info["size"] = size
            goal = f"Move all the {SIZE_WORD[size]} blocks in the {area1} area to the {area2} area."
        else:
            goal = f"Move all the blocks in the {area1} area to the {area2} area."
        return Scene(sp.objects, goal, info)

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        """One goal: each selected block to a free spot in area2 (big blocks first); a block may
        take any spot computed for a block at least its size (pose metric, 0.01 m)."""
        objs = sorted((scene.by_id(i) for i in scene.info["selected"]), key=lambda o: (-o.footprint_radius, o.obj_id))
        radii = [o.footprint_radius for o in objs]
        try:
            spots = free_positions(scene.objects, scene.info["area2"], radii)
        except ValueError as e:  # pragma: no cover - scenes leave area2 empty
            from capmj.errors import TaskError

            raise TaskError(f"{self.name}: {e}") from None
        targets = tuple(Target((x, y, o.height / 2), None) for (x, y), o in zip(spots, objs))
        matches = tuple(tuple(int(rj >= ri - 1e-12) for rj in radii) for ri in radii)
        return [OracleGoal(tuple(o.obj_id for o in objs), targets, matches, metric="pose", tolerance=P.PLANE_TOL)]

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        area2 = scene.info["area2"]
        sel = set(scene.info["selected"])
        start = scene.info["start_positions"]
        met, diags = 0, []
        for i in scene.info["blocks"]:
            s = state.spec(i)
            p = state.pos(i)
            if i in sel:
                if P.in_area(p, area2):
                    met += 1
                else:
                    diags.append(f"{label(s)} is not in the {area2} area (at x = {p[0]:.3f}, y = {p[1]:.3f})")
            else:
                if P.moved_less_than(state, i, start[str(i)], P.MOVE_TOL):
                    met += 1
                else:
                    d = float(np.linalg.norm(p - np.asarray(start[str(i)])))
                    diags.append(f"{label(s)} should stay put but moved {d:.3f} m (max {P.MOVE_TOL})")
        n = len(scene.info["blocks"])
        ok = met == n
        if ok:
            diags.append(f"all {len(sel)} block(s) moved to the {area2} area, the others stayed")
        return verdict(met, n, ok, diags)


class MoveBlocksBetweenAbsolutePositions(AreaMoveTask):
    """Move every block of one quadrant area to another quadrant area.

    Task Description:
        "Move all the blocks in the {area1} area to the {area2} area."  Areas are quadrants of
        the workspace named like the front camera image: top = x ∈ [0.25, 0.5], bottom = x ∈
        [0.5, 0.75], left = y < 0, right = y > 0.  3–4 blocks (big or small) start in area1,
        1–3 more in the two other quadrants, none in area2.

    Randomizations:
        The ordered pair of distinct quadrants, numbers and sizes of the blocks, colours
        (distinct), spawn order, all poses and yaws (centres ≥ 0.02 m from area borders).

    Success Conditions:
        Every block that started in area1 ends with its centre in area2; every other block ends
        within 0.03 m (3-D) of its start.  Progress = blocks meeting their condition / blocks.
    """

    name = "move-blocks-between-absolute-positions"
    by_size = False


TASK = MoveBlocksBetweenAbsolutePositions()
