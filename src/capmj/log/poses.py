"""Body poses buffered between flushes of an episode log, and the rows worth sending.

Frames arrive every 25 physics steps with the pose of every body (~300 frames of ~20 bodies per
episode).  Handling them body by body and frame by frame in Python was a large share of an
episode's wall time (``docs/speed.md``, "Episode logs"), so a frame is kept as the two arrays it arrives as, and a flush stacks
the frames into one ``(frames, bodies, 7)`` array and chooses the rows to send for all bodies at
once (:func:`changed_rows`): one short loop over frames, none over bodies.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

POSE_EPS = 1e-5
"""A body's pose is re-sent only when it moved more than this (m / quaternion units, per
component) since the pose last sent: resting blocks cost one row."""


@dataclass(frozen=True)
class PoseTable:
    """Frames stacked: ``poses[f, b]`` is body ``names[b]``'s ``[x, y, z, qw, qx, qy, qz]`` in frame
    ``f``, where ``present[f, b]`` (a frame need not hold every body)."""

    names: tuple[str, ...]      # bodies in the order they first appear
    times: np.ndarray           # (F,) float64, episode seconds
    labels: np.ndarray          # (F,) int64, primitive index
    poses: np.ndarray           # (F, B, 7) float64
    present: np.ndarray         # (F, B) bool


class PoseBuffer:
    """Frames waiting for a flush, each flagged whether it is kept (written) or only buffered."""

    def __init__(self) -> None:
        self._frames: list[tuple[float, int, tuple[str, ...], np.ndarray, np.ndarray]] = []
        self._keep: list[bool] = []

    def __len__(self) -> int:
        return len(self._frames)

    def add(self, time: float, label: int, names: tuple[str, ...], pos: np.ndarray, quat: np.ndarray,
            keep: bool) -> None:
        self._frames.append((time, label, names, pos, quat))
        self._keep.append(keep)

    def keep_last(self) -> None:
        """Keep the latest frame whatever its turn (the state at the end of a primitive)."""
        if self._keep:
            self._keep[-1] = True

    def take(self) -> PoseTable | None:
        """The kept frames and the latest one, stacked; the buffer is emptied.  None if it was empty."""
        if not self._frames:
            return None
        last = len(self._frames) - 1
        frames = [f for i, (f, k) in enumerate(zip(self._frames, self._keep)) if k or i == last]
        self._frames, self._keep = [], []
        return _stack(frames)


def _stack(frames: Sequence[tuple[float, int, tuple[str, ...], np.ndarray, np.ndarray]]) -> PoseTable:
    columns: dict[str, int] = {}
    index: dict[tuple[str, ...], np.ndarray] = {}  # a frame's bodies -> their columns
    for _, _, names, _, _ in frames:
        if names not in index:
            for n in names:
                columns.setdefault(n, len(columns))
            index[names] = np.array([columns[n] for n in names], dtype=np.intp)
    poses = np.zeros((len(frames), len(columns), 7))
    present = np.zeros((len(frames), len(columns)), dtype=bool)
    for f, (_, _, names, pos, quat) in enumerate(frames):
        cols = index[names]
        poses[f, cols, :3] = pos
        poses[f, cols, 3:] = quat
        present[f, cols] = True
    return PoseTable(tuple(columns), np.array([f[0] for f in frames], dtype=np.float64),
                     np.array([f[1] for f in frames], dtype=np.int64), poses, present)


def changed_rows(poses: np.ndarray, present: np.ndarray, last: np.ndarray, sent: np.ndarray,
                 eps: float = POSE_EPS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which rows of ``poses`` (F, B, 7) to send: a body's row is sent unless a pose was sent for
    that body before (``sent[b]``, the last one ``last[b]``) and no component differs from it by
    ``eps`` or more.  Sequential per body (each sent row becomes the reference), vectorised over
    bodies.  Returns the (F, B) mask and the updated ``last`` and ``sent``."""
    keep = np.zeros(present.shape, dtype=bool)
    last, sent = last.copy(), sent.copy()
    for f in range(len(poses)):
        # ``~(d < eps)``, not ``d >= eps``: a pose with NaNs is sent, as any pose that is not close
        k = present[f] & ~(sent & (np.abs(poses[f] - last).max(axis=1) < eps))
        keep[f] = k
        last[k] = poses[f, k]
        sent |= k
    return keep, last, sent


__all__ = ["POSE_EPS", "PoseBuffer", "PoseTable", "changed_rows"]
