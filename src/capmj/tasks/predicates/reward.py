"""The Ravens-style matching reward over the final state, and the matching it rests on."""

from __future__ import annotations

import math
from typing import Sequence

from capmj.sim.pose import to_frame_2d
from capmj.sim.state import SceneState
from capmj.tasks.predicates.tolerances import YAW_TOL, Z_TOL


def _pose_match(state: SceneState, obj_id: int, goal, target) -> bool:
    p = state.pos(obj_id)
    t = target.pos
    if goal.metric == "zone":
        half = goal.zone_size / 2
        lx, ly = to_frame_2d(p[:2], target.yaw or 0.0, t[:2])
        return abs(lx) <= half and abs(ly) <= half
    if math.hypot(p[0] - t[0], p[1] - t[1]) > goal.tolerance or abs(p[2] - t[2]) > Z_TOL:
        return False
    if goal.rotations and target.yaw is not None:
        sym = math.pi / 2 if state.spec(obj_id).kind == "block" else 2 * math.pi
        err = (state.poses[obj_id].yaw - target.yaw) % sym
        if min(err, sym - err) > YAW_TOL:
            return False
    return True


def max_matching(adj: Sequence[Sequence[int]], n_targets: int) -> int:
    """Size of a maximum bipartite matching of objects to targets, ``adj[i]`` listing the targets
    (``0 <= j < n_targets``) object ``i`` may take (Kuhn's augmenting paths; goals are small)."""
    owner = [-1] * n_targets

    def augment(i: int, seen: list[bool]) -> bool:
        for j in adj[i]:
            if seen[j]:
                continue
            seen[j] = True
            if owner[j] < 0 or augment(owner[j], seen):
                owner[j] = i
                return True
        return False

    return sum(augment(i, [False] * n_targets) for i in range(len(adj)))


def ravens_reward(goals: Sequence, state: SceneState) -> float:
    """Ravens-style matching reward in [0, 1] over the final state.

    Each object of each goal that sits at a target it may go to counts one; the reward is the
    count divided by the total number of objects over all goals.  Assignment is one-to-one within
    a goal (a maximum matching, so two objects never share one slot) unless the goal has
    ``replace``.  Pose metric: xy within ``goal.tolerance`` and z within 0.015 m of the target
    (and, with ``rotations`` and a target yaw, yaw within 15° modulo the block's 90° symmetry);
    zone metric: centre inside the square of side ``goal.zone_size`` around the target (rotated
    by the target yaw when given).  Goals with no objects are ignored; no goals give 0.
    """
    total = 0
    matched = 0
    for g in goals:
        if not g.objects:
            continue
        total += len(g.objects)
        adj = [[j for j, t in enumerate(g.targets) if g.matches[i][j] and _pose_match(state, oid, g, t)]
               for i, oid in enumerate(g.objects)]
        matched += sum(1 for a in adj if a) if g.replace else max_matching(adj, len(g.targets))
    return matched / total if total else 0.0


__all__ = ["max_matching", "ravens_reward"]
