"""Joint-space path planning around obstacles: OMPL's RRT-Connect, then path simplification.

Why OMPL: it is the planning library of MoveIt, its PyPI wheel (``ompl``) ships the C++ planners
with Python bindings, and RRT-Connect (Kuffner & LaValle 2000) is the standard choice for a
single arm query: two trees grown towards each other, fast in the narrow free space over a
cluttered table.  The path it finds is shortened by OMPL's :class:`PathSimplifier` (shortcutting,
vertex reduction).  Validity is capmj's own: a configuration is valid when the
:class:`~capmj.sim.collision.CollisionChecker` finds no contact its
:class:`~capmj.sim.collision.Allowance` does not cover, and every edge of the result is checked
again densely by that checker (OMPL's own edge check samples at a resolution it derives from the
space's extent).

Deterministic: OMPL's random generator is seeded, before each query, from the caller's seed and
the query itself (start, goal, the world's state), so one query gives one path in every process,
however many queries came before.  The effort is bounded by a number of configuration checks, not
wall time, so the outcome does not depend on the machine; a wall-time guard only stops a runaway.
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

MAX_CHECKS = 30000
"""Configuration checks one query may spend before it gives up (a few tenths of a second)."""

WALL_GUARD_S = 2.0
"""Seconds after which a query stops whatever its check count (a guard against a runaway; never
reached by a query within ``MAX_CHECKS``)."""

BOUND_MARGIN = 1.2
"""rad: the search is bounded per joint to the span of start and goal widened by this (within the
joint limits): arm paths around a tower never need a joint to swing far beyond both ends."""


@dataclass(frozen=True)
class JointPath:
    """A planned joint-space path: waypoints (rows; the first is the start, the last the goal),
    straight in joint space between them, and what it cost (configuration checks, seconds)."""

    waypoints: np.ndarray
    checks: int
    seconds: float


def query_seed(seed: int, *arrays: np.ndarray) -> int:
    """A 31-bit seed from ``seed`` and the exact bytes of ``arrays`` (the query): the same query
    gets the same seed in every process (no Python hash randomisation)."""
    h = hashlib.sha256(int(seed).to_bytes(8, "little", signed=True))
    for a in arrays:
        h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    return int.from_bytes(h.digest()[:4], "little") & 0x7FFFFFFF or 1


def plan_joint_path(valid: Callable[[np.ndarray], bool], edge_clear: Callable[[np.ndarray], bool],
                    q_start: np.ndarray, q_goal: np.ndarray, lo: np.ndarray, hi: np.ndarray, seed: int,
                    resolution: float, max_checks: int = MAX_CHECKS) -> JointPath | None:
    """A path from ``q_start`` to ``q_goal`` on which ``valid`` holds, or None if none was found
    within ``max_checks`` calls of ``valid``.  ``edge_clear(waypoints)`` re-checks the simplified
    result densely (a path it rejects is not returned).  ``lo``/``hi`` are the joint limits,
    ``resolution`` (rad) the largest joint step between configurations OMPL checks on an edge,
    ``seed`` the query's seed (:func:`query_seed`)."""
    if not valid(q_start) or not valid(q_goal):
        return None  # RRT-Connect would wait for a valid goal until its budget ends
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LOG_NONE)
    ou.RNG.setSeed(int(seed))  # before the planner and its samplers draw their own seeds
    n = len(q_start)
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    span_lo = np.maximum(lo, np.minimum(q_start, q_goal) - BOUND_MARGIN)
    span_hi = np.minimum(hi, np.maximum(q_start, q_goal) + BOUND_MARGIN)
    for i in range(n):
        bounds.setLow(i, float(span_lo[i]))
        bounds.setHigh(i, float(span_hi[i]))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    calls = [0]
    q = np.empty(n)

    def state_valid(state: object) -> bool:
        calls[0] += 1
        for i in range(n):
            q[i] = state[i]  # type: ignore[index]
        return bool(valid(q))

    setup.setStateValidityChecker(state_valid)
    si = setup.getSpaceInformation()
    si.setStateValidityCheckingResolution(resolution / max(space.getMaximumExtent(), 1e-9))
    setup.setPlanner(og.RRTConnect(si))
    start, goal = space.allocState(), space.allocState()
    for i in range(n):
        start[i], goal[i] = float(q_start[i]), float(q_goal[i])
    setup.setStartAndGoalStates(start, goal)
    t0 = time.perf_counter()
    budget = ob.PlannerTerminationCondition(lambda: calls[0] >= max_checks or time.perf_counter() - t0 > WALL_GUARD_S)
    setup.solve(budget)
    if not setup.haveExactSolutionPath():
        return None
    path = setup.getSolutionPath()
    og.PathSimplifier(si).simplifyMax(path)  # deterministic: no time limit
    waypoints = np.array([[path.getState(k)[i] for i in range(n)] for k in range(path.getStateCount())])
    waypoints[0], waypoints[-1] = q_start, q_goal
    if not edge_clear(waypoints):
        return None
    return JointPath(waypoints, calls[0], time.perf_counter() - t0)
