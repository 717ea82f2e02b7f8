"""The oracle: solves a task from its Ravens-style oracle goals alone, through real pick-and-place.

Like the Ravens oracle it takes goals in order, matches each remaining object to the nearest
allowed free target, masks used targets (one-to-one unless ``replace``), and skips objects already
in place.  Unlike it, it first clears a target that another object occupies, and it never
teleports anything.
"""

from __future__ import annotations

import math

import numpy as np

from capmj.agents.base import EpisodeContext
from capmj.errors import AgentError
from capmj.sim.bounds import WORKSPACE
from capmj.tasks.predicates import max_matching
from capmj.tasks.protocol import OracleGoal, Target
from capmj.tasks.spawn import free_positions

IN_PLACE_DIST = 0.005
"""An object whose centre is this close (m, 3-D) to its target is left where it is: half the success
predicates' 0.01 m plane tolerance, so what the oracle skips still passes with margin, while an
object a few millimetres off is not picked and placed again for nothing."""
IN_PLACE_YAW = math.radians(5.0)
"""With a target yaw, an object also counts as in place only within this angle (rad) of it, a third
of the predicates' 15° rotation tolerance."""
YAW_PERIOD = math.pi / 2
"""Yaws are compared modulo a quarter turn, the symmetry of the blocks that get yaw targets (a cube
looks the same every 90°)."""
BLOCKER_MARGIN = 0.04
"""A movable object blocks a target when its centre is closer (m, in xy) than its own footprint
radius plus this: about the footprint radius of the object coming in (0.028 m for a small block,
0.042 m for a big one), so the two would overlap."""
BLOCKER_BELOW = 0.1
"""Only objects whose centre is above the target height minus this (m) can block it: what lies far
below (e.g. the bottom of a stack the target sits on) is support, not in the way."""
CLEAR_RESERVE = 0.08
"""An object cleared off a target is put down at least this far (m, plus its radius and the spawn
gap) from the target's xy, so it does not land back in the way of the object about to go there."""


def _completable(matches: np.ndarray, rows: list[int], cols: list[int]) -> bool:
    """Whether every row (object) can get its own column (target) among ``cols``."""
    adj = [[c for c in cols if matches[r, c]] for r in rows]
    return max_matching(adj, matches.shape[1]) == len(rows)


class OracleAgent:
    name = "oracle"
    model = None

    def act(self, ctx: EpisodeContext) -> None:
        for goal in ctx.task.oracle_goals(ctx.scene):
            self._solve_goal(ctx, goal)

    # ------------------------------------------------------------------ one goal
    def _solve_goal(self, ctx: EpisodeContext, goal: OracleGoal) -> None:
        w = ctx.world
        matches = np.asarray(goal.matches, dtype=bool)
        remaining = list(range(len(goal.objects)))
        used: set[int] = set()
        while remaining:
            free = [j for j in range(len(goal.targets)) if goal.replace or j not in used]
            pairs = sorted(
                (float(np.linalg.norm(np.asarray(w.pose(goal.objects[i]).pos) - np.asarray(goal.targets[j].pos))), i, j)
                for i in remaining for j in free if matches[i, j]
            )
            # Nearest pair first, but only one that still leaves every other object a target.
            best = next((p for p in pairs if goal.replace or _completable(matches, [i for i in remaining if i != p[1]],
                                                                          [j for j in free if j != p[2]])), None)
            if best is None:
                raise AgentError(f"oracle: no free target left for objects {[goal.objects[i] for i in remaining]}")
            dist, i, j = best
            obj, target = goal.objects[i], goal.targets[j]
            remaining.remove(i)
            used.add(j)
            if dist < IN_PLACE_DIST and self._yaw_ok(ctx, obj, target):
                continue  # already in place
            self._clear(ctx, target, keep={obj})
            res = ctx.pick_and_place(np.asarray(w.pose(obj).pos), np.asarray(target.pos), target.yaw)
            if not res.ok:
                raise AgentError(f"oracle: pick-and-place of object {obj} failed: {res.status} {res.message}")
            ctx.notes.setdefault("placed", []).append(obj)

    @staticmethod
    def _yaw_ok(ctx: EpisodeContext, obj: int, target: Target) -> bool:
        if target.yaw is None:
            return True
        d = (ctx.world.pose(obj).yaw - target.yaw + YAW_PERIOD / 2) % YAW_PERIOD - YAW_PERIOD / 2
        return abs(d) < IN_PLACE_YAW

    def _clear(self, ctx: EpisodeContext, target: Target, keep: set[int]) -> None:
        """Move away movable objects sitting where the target object must go (top first)."""
        w = ctx.world
        placed = set(ctx.notes.get("placed", []))
        tx, ty, tz = target.pos
        blockers = []
        for o in w.objects:
            if o.fixed or o.obj_id in keep or o.obj_id in placed:
                continue
            p = np.asarray(w.pose(o.obj_id).pos)
            if math.hypot(p[0] - tx, p[1] - ty) < o.footprint_radius + BLOCKER_MARGIN and p[2] > tz - BLOCKER_BELOW:
                blockers.append((-p[2], o.obj_id))
        for _, oid in sorted(blockers):
            state = w.state()
            current = [o.moved(state.poses[o.obj_id].pos) for o in w.objects if o.obj_id != oid]
            spot = free_positions(current, WORKSPACE.xy, [w.objects_by_id[oid].footprint_radius],
                                  reserved=[((tx, ty), CLEAR_RESERVE)])[0]
            res = ctx.pick_and_place(np.asarray(w.pose(oid).pos), np.array(spot))
            if not res.ok:
                raise AgentError(f"oracle: could not clear object {oid} from the target: {res.status}")
