"""The episode's ``sim_time`` timeline: simulated time made monotonic across re-plan resets."""

from __future__ import annotations

import math

RESET_GAP_S = 0.05
"""sim_time gap inserted where the world was reset (one frame period)."""


class EpisodeClock:
    """Maps raw simulated times to episode times.

    A re-plan restores the world's initial state, so the raw simulated time jumps back; the log's
    timeline must not (the second attempt would overwrite the first).  Only frames (which come
    from stepping the world) can reveal a reset; other events are placed at their time or, if that
    lies in the past of the log (a stale time, or a text logged right after a reset), at the latest
    logged time.
    """

    def __init__(self) -> None:
        self.offset = 0.0        # added to raw times after a reset
        self.now = 0.0           # latest episode time
        self._last_raw = -math.inf

    def event(self, t: float | None) -> float:
        """Episode time of a non-frame event at raw time ``t`` (None: now)."""
        if t is None:
            return self.now
        self.now = max(float(t) + self.offset, self.now)
        return self.now

    def frame(self, t: float) -> tuple[float, bool]:
        """Episode time of a frame at raw time ``t``, and whether it is the first after a reset."""
        t = float(t)
        reset = t < self._last_raw - 1e-9
        if reset:  # continue the timeline after a small gap
            self.offset += self._last_raw - t + RESET_GAP_S
        self._last_raw = t
        self.now = max(self.now, t + self.offset)
        return t + self.offset, reset


__all__ = ["EpisodeClock", "RESET_GAP_S"]
