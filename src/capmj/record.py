"""The episode event sink: what an episode reports for logs, independent of any log format.

Every layer may emit events through a :class:`Recorder` without knowing where they go; the rerun
writer in :mod:`capmj.log` implements it, and :class:`NullRecorder` is the default so that running
an episode never requires a logger.  A recorder that stores poses by the thousand may also take
them as arrays (:class:`ArrayFrames`), which spares the runner building a dict of tuples per frame.
"""

from __future__ import annotations

from typing import Any, Mapping, Protocol, runtime_checkable

import numpy as np


class Recorder(Protocol):
    def attach(self, world: Any) -> None:
        """The episode's live ``World``, once built and settled (exact shapes, camera images)."""

    def frame(self, time: float, poses: Mapping[str, tuple[tuple[float, ...], tuple[float, ...]]]) -> None:
        """Poses of named bodies, ``(pos, quat_wxyz)``, at simulated ``time``."""

    def primitive(self, index: int, time: float, info: Mapping[str, Any]) -> None:
        """A finished primitive: its targets and outcome."""

    def text(self, path: str, body: str, time: float | None = None) -> None:
        """A text document (goal, prompt, completion, code, report, verdict…)."""

    def image(self, path: str, rgb: np.ndarray, time: float | None = None) -> None:
        """An RGB image (uint8 HxWx3)."""

    def depth(self, path: str, depth: np.ndarray, time: float | None = None) -> None:
        """A metric depth image (float32 metres)."""

    def close(self) -> None:
        ...


@runtime_checkable
class ArrayFrames(Protocol):
    """The array form of :meth:`Recorder.frame`, for recorders that offer it (the runner prefers it)."""

    def frame_arrays(self, time: float, names: tuple[str, ...], pos: np.ndarray, quat: np.ndarray) -> None:
        """Poses of the bodies ``names`` at simulated ``time``: ``pos`` (N, 3) and ``quat``
        (N, 4, MuJoCo's w, x, y, z) rows in ``names`` order.  The arrays are the recorder's to keep: the caller passes
        fresh copies."""


class NullRecorder:
    """Records nothing."""

    def attach(self, world) -> None:  # noqa: D102
        pass

    def frame(self, time, poses) -> None:  # noqa: D102
        pass

    def primitive(self, index, time, info) -> None:  # noqa: D102
        pass

    def text(self, path, body, time=None) -> None:  # noqa: D102
        pass

    def image(self, path, rgb, time=None) -> None:  # noqa: D102
        pass

    def depth(self, path, depth, time=None) -> None:  # noqa: D102
        pass

    def close(self) -> None:  # noqa: D102
        pass
