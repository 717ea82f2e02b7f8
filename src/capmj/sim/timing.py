"""Time-optimal timing of a joint-space path under joint speed and acceleration limits.

Why: a straight tool line is first solved into a joint-space path ``q(s)``, ``s`` in [0, 1]
(:class:`capmj.sim.motion.Motion`).  Timing it with one Cartesian trapezoid and then slowing the
*whole* line down until the worst joint is within its limits (the first version) wasted time: on
most lines one joint is near its limit for a short stretch only, yet every stretch ran slower
(``docs/speed.md``).  Here the path speed ``ṡ``
follows, point by point, the fastest profile from rest to rest under the tool's speed and
acceleration caps and the fastest joint's ``|q'| ṡ <= v_max`` and ``|q'| |s̈| <= a_max``: the
bang-bang solution of time-optimal path parameterisation (Bobrow 1985; TOPP-RA states it
today), without the path-curvature term ``q'' ṡ²`` of the joint acceleration, for which the
caller leaves a share of the acceleration limit.  On a grid, ``x = ṡ²`` rises at most ``2 a ds``
per interval, so the forward limit is ``min over s' <= s of cap(s') + 2 ∫_{s'}^{s} a`` (and the
backward one alike): two running minima, vectorised, instead of a loop over grid points (a
loop in Python cost more time than the faster timing saved).  The path is unchanged; only its
timing is.  :meth:`Motion.plan_line` checks the sampled trajectory against the full limits
afterwards and slows the whole timing down if something slipped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DERIVATIVE_EPS = 1e-9
"""A fastest-joint rate ``|dq/ds|`` below this counts as this (a pure standstill of every joint
cannot occur on a line of non-zero length; the floor only avoids a division by zero)."""


@dataclass(frozen=True)
class Timing:
    """Path parameter against time: at grid points ``s`` (ascending, 0 to 1) the path speed ``sd``
    (ds/dt) and time ``t``; the path acceleration ``u`` is constant on each interval.
    ``slowdown`` is how far below the Cartesian speed cap the joints' limits force the path
    somewhere (1 when they never do), so a caller can refuse a line that would crawl."""

    s: np.ndarray    # (n + 1,)
    sd: np.ndarray   # (n + 1,)
    u: np.ndarray    # (n,)
    t: np.ndarray    # (n + 1,)
    slowdown: float

    @property
    def total(self) -> float:
        return float(self.t[-1])

    def at(self, times: np.ndarray) -> np.ndarray:
        """Path parameters at ``times`` (seconds, clipped to the timing), vectorised."""
        times = np.clip(np.asarray(times, float), 0.0, self.total)
        i = np.clip(np.searchsorted(self.t, times, side="right") - 1, 0, len(self.u) - 1)
        tau = times - self.t[i]
        s = self.s[i] + self.sd[i] * tau + 0.5 * self.u[i] * tau * tau
        return np.clip(s, self.s[i], self.s[i + 1])


def time_optimal(s: np.ndarray, dq: np.ndarray, speed_cap: np.ndarray, accel_cap: float,
                 joint_speed: float, joint_accel: float) -> Timing:
    """The fastest timing of a path from rest to rest.

    ``s`` are grid points (ascending, 0 to 1), ``dq`` the path's derivative there (``(n + 1,
    joints)``), ``speed_cap`` the Cartesian cap on ``ṡ`` at each point and ``accel_cap`` on
    ``|s̈|`` (both in path units: m/s over the path's length).
    """
    n = len(s) - 1
    if n < 1:
        raise ValueError(f"a timing needs at least two grid points, got {len(s)}")
    rate = np.max(np.abs(dq), axis=1)                       # the fastest joint's |dq/ds|
    inv = 1.0 / np.maximum(rate, DERIVATIVE_EPS)
    cap = np.asarray(speed_cap, float)
    joint_cap = joint_speed * inv
    x_cap = np.minimum(cap, joint_cap) ** 2
    accel = np.minimum(accel_cap, joint_accel * inv)
    ds = np.diff(s)
    rise = 2.0 * np.minimum(accel[:-1], accel[1:]) * ds   # largest change of x over each interval
    # Forward: x(s) = min over s' <= s of x_cap(s') + (F(s) - F(s')), F the cumulative rise, with
    # x(0) = 0 (from rest); backward the same from the end (to rest); the timing takes the lower.
    f = np.concatenate([[0.0], np.cumsum(rise)])
    start = x_cap.copy()
    start[0] = 0.0
    forward = f + np.minimum.accumulate(start - f)
    g = f[-1] - f
    end = x_cap.copy()
    end[-1] = 0.0
    backward = g + np.minimum.accumulate((end - g)[::-1])[::-1]
    x = np.minimum(forward, backward)
    sd = np.sqrt(x)
    u = np.diff(x) / (2.0 * ds)
    denom = sd[:-1] + sd[1:]
    dt = 2.0 * ds / np.where(denom > 0, denom, np.inf)
    slowdown = float(np.max(cap / joint_cap))
    return Timing(np.asarray(s, float), sd, u, np.concatenate([[0.0], np.cumsum(dt)]), slowdown)
