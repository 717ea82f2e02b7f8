"""Generated task 9: zone-bisector."""

from __future__ import annotations

import math

import numpy as np

from capmj.sim.objects import BLOCK_SIZES, ObjectSpec, resting_z
from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Resample, Scene, Target, Verdict
from capmj.tasks.spawn import SPAWN_BOUNDS, Spawner, centre_bounds, pick_colors
from capmj_tasks.common import EXTENDED, BenchTask, label, verdict

BLOCK = BLOCK_SIZES["small"]
PITCH = 2 * BLOCK
"""Neighbour centre spacing (m): the gap between block edges equals the block size."""
HALF_DISTANCE = (0.13, 0.2)
"""Distance (m) from each zone centre to the bisector: ≥ 0.13 keeps the row's middle block clear
of both zones at any zone yaw."""
TRIES = 200

GOAL = ("Arrange all blocks on the zone bisector line between two symmetrically placed zones evenly on the "
        "tabletop, and the gap between two adjacent blocks' edges should be near the block size, and the line "
        "connecting the center of the zones also bisects these blocks.")


def row_geometry(c1, c2) -> tuple[np.ndarray, np.ndarray]:
    """(midpoint of the zone centres, unit direction of their perpendicular bisector) in xy."""
    c1, c2 = np.asarray(c1, float)[:2], np.asarray(c2, float)[:2]
    d = (c2 - c1) / np.linalg.norm(c2 - c1)
    return (c1 + c2) / 2, np.array([-d[1], d[0]])


def row_slots(mid, direction, n: int) -> np.ndarray:
    """(n, 2) centres of an evenly spaced row of ``n`` blocks centred on ``mid``."""
    return np.array([mid + (i - (n - 1) / 2) * PITCH * direction for i in range(n)])


class ZoneBisector(BenchTask):
    """Line the blocks up on the perpendicular bisector of two mirrored zones, evenly spaced.

    Task Description:
        The goal text is fixed (see ``GOAL``): arrange all blocks on the bisector line between two
        zones, the gap between neighbouring blocks' edges about the block size, the line through
        the zone centres cutting the row in half.  Two zones mirrored about a line and 4–6 small
        blocks; the row's spots are kept free at reset, inside the reachable workspace.
    Randomizations:
        Number of blocks (4–6), block and zone colours, the midpoint, the direction and the half
        distance (0.13–0.2 m) of the zone pair, the first zone's yaw (the second is its mirror
        image), all block poses and yaws.
    Success Conditions:
        ``predicates.row_on_line`` over all blocks with the bisector as the line and the midpoint
        of the zone centres as the row's midpoint: every centre within 0.015 m of the line,
        neighbour centre spacing 0.08 m (2 × block size) ± 0.015, the mean of the centres within
        0.02 m of the midpoint; every block upright and resting on the table.  Progress = (blocks
        on the line and on the table + good gaps + 1 for the midpoint) / (2 n).
    """

    name = "zone-bisector"
    tags = EXTENDED

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        n = int(rng.integers(4, 7))
        zc = pick_colors(rng, 2)
        zone_r = ObjectSpec(1, "zone", zc[0], (0.0, 0.0, 0.0)).footprint_radius
        zb, rb = centre_bounds(zone_r), SPAWN_BOUNDS
        for _ in range(TRIES):
            mid = rng.uniform((rb.xmin, rb.ymin), (rb.xmax, rb.ymax))
            theta = float(rng.uniform(0.0, math.pi))
            h = float(rng.uniform(*HALF_DISTANCE))
            d = np.array([math.cos(theta), math.sin(theta)])
            c1, c2 = mid - h * d, mid + h * d
            slots = row_slots(mid, np.array([-d[1], d[0]]), n)
            if (all(zb.contains(c[0], c[1]) for c in (c1, c2))
                    and bool(np.all(rb.contains(slots[:, 0], slots[:, 1])))):
                break
        else:
            raise Resample("no room for two zones and the row")
        yaw1 = float(rng.uniform(0.0, math.pi / 2))
        yaw2 = 2 * (theta + math.pi / 2) - yaw1  # mirror image about the bisector
        sp = Spawner(rng)
        z = resting_z("zone")
        zones = [sp.add(ObjectSpec(sp.next_id, "zone", zc[0], (c1[0], c1[1], z), yaw1)),
                 sp.add(ObjectSpec(sp.next_id, "zone", zc[1], (c2[0], c2[1], z), yaw2 % (2 * math.pi)))]
        block_r = ObjectSpec(1, "block", "red", (0.0, 0.0, 0.0), size="small").footprint_radius
        for s in slots:
            sp.reserve(s, block_r)
        blocks = [sp.block(c, "small") for c in pick_colors(rng, n)]
        return Scene(sp.objects, GOAL, {"zones": [zn.obj_id for zn in zones], "blocks": [b.obj_id for b in blocks]})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        """One goal: every block to any spot of the row (one-to-one), lined up with the row."""
        z1, z2 = (scene.by_id(i) for i in scene.info["zones"])
        mid, e = row_geometry(z1.pos, z2.pos)
        blocks = [scene.by_id(i) for i in scene.info["blocks"]]
        yaw = math.atan2(e[1], e[0])
        targets = tuple(Target((float(x), float(y), BLOCK / 2), yaw) for x, y in row_slots(mid, e, len(blocks)))
        return [OracleGoal(tuple(b.obj_id for b in blocks), targets, tuple((1,) * len(targets) for _ in blocks),
                           metric="pose", tolerance=P.PLANE_TOL)]

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        ids = scene.info["blocks"]
        z1, z2 = scene.info["zones"]
        mid, e = row_geometry(state.pos(z1), state.pos(z2))
        rep = P.row_on_line([state.pos(i) for i in ids], mid, e, PITCH)
        diags: list[str] = []
        met = 0
        for k, i in enumerate(ids):
            lab = label(state.spec(i))
            flat = P.resting_on_table(state, i) and not P.toppled(state, i)
            on_line = rep.offsets[k] <= P.ROW_LINE_TOL
            met += flat and on_line
            if not flat:
                diags.append(f"{lab} is not upright on the table (z = {state.pos(i)[2]:.3f} m, "
                             f"tilt {math.degrees(state.poses[i].tilt):.0f}°)")
            if not on_line:
                diags.append(f"{lab} is {rep.offsets[k]:.3f} m off the bisector (max {P.ROW_LINE_TOL})")
        for k, g in enumerate(rep.gaps):
            a, b = (label(state.spec(ids[rep.order[j]])) for j in (k, k + 1))
            if abs(g - PITCH) <= P.ROW_PITCH_TOL:
                met += 1
            else:
                diags.append(f"{a} and {b} are {g:.3f} m apart (need {PITCH:.2f} ± {P.ROW_PITCH_TOL})")
        if rep.midpoint_error <= P.ROW_MID_TOL:
            met += 1
        else:
            diags.append(f"the row's midpoint is {rep.midpoint_error:.3f} m from the midpoint of the zone centres "
                         f"(max {P.ROW_MID_TOL})")
        ok = met == 2 * len(ids)  # every block, gap and the midpoint: exactly rep.ok plus flat blocks
        if ok:
            diags.append(f"{len(ids)} blocks evenly spaced on the bisector, centred between the zones")
        return verdict(met, 2 * len(ids), ok, diags)


TASK = ZoneBisector()
