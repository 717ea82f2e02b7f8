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
from capmj.tasks.protocol import OracleGoal, Target
from capmj.tasks.spawn import free_positions


def _completable(matches: np.ndarray, rows: list[int], cols: list[int]) -> bool:
    """Whether every row can get its own column (augmenting-path bipartite matching)."""
    owner: dict[int, int] = {}

    def augment(r: int, seen: set[int]) -> bool:
        for c in cols:
            if matches[r, c] and c not in seen:
                seen.add(c)
                if c not in owner or augment(owner[c], seen):
                    owner[c] = r
                    return True
        return False

    return all(augment(r, set()) for r in rows)


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
            if dist < 0.005 and self._yaw_ok(ctx, obj, target):
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
        d = (ctx.world.pose(obj).yaw - target.yaw + math.pi / 4) % (math.pi / 2) - math.pi / 4
        return abs(d) < math.radians(5)

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
            if math.hypot(p[0] - tx, p[1] - ty) < o.footprint_radius + 0.04 and p[2] > tz - 0.1:
                blockers.append((-p[2], o.obj_id))
        for _, oid in sorted(blockers):
            state = w.state()
            current = [o.moved(state.poses[o.obj_id].pos) for o in w.objects if o.obj_id != oid]
            spot = free_positions(current, WORKSPACE.xy, [w.by_id[oid].footprint_radius],
                                  reserved=[((tx, ty), 0.08)])[0]
            res = ctx.pick_and_place(np.asarray(w.pose(oid).pos), np.array(spot))
            if not res.ok:
                raise AgentError(f"oracle: could not clear object {oid} from the target: {res.status}")
