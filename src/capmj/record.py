"""The episode event sink: what an episode reports for logs, independent of any log format.

Every layer may emit events through a :class:`Recorder` without knowing where they go; the rerun
writer in :mod:`capmj.log` implements it, and :class:`NullRecorder` is the default so that running
an episode never requires a logger.  A recorder that stores poses by the thousand may also take
them as arrays (:class:`ArrayFrames`), which spares the runner building a dict of tuples per frame.
A recorder that draws what the robot perceived (``--perception rgbd``) also implements
:class:`PerceptionViews`: after every perception call it is sent the planner API's objects as
:class:`PerceivedBox` records, each already judged against the truth, with the call's errors.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal, Mapping, Protocol, Sequence, runtime_checkable

import numpy as np

from capmj.records.perception import PerceptionCall

MatchStatus = Literal["right", "wrong", "false"]
"""How a perceived object compares to the truth: ``right`` (matched, kind, colour and size right,
centre within the error tolerance), ``wrong`` (matched, but a label wrong or the centre off),
``false`` (no true object there)."""


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


@dataclass(frozen=True)
class PerceivedBox:
    """One object of the planner API's view after a perception call, as a box to draw.

    The box is the detection's footprint: a square with its yaw for blocks and zones, else its
    axis-aligned box (yaw 0).  ``visible`` is False for a block the tracker keeps although it is
    hidden in a tower (drawn at its remembered pose)."""

    obj_id: int
    name: str
    """The planner-facing name (``movable small red block with obj_id 3``)."""
    center: tuple[float, float, float]
    half_size: tuple[float, float, float]
    yaw: float
    confidence: float
    visible: bool
    match: MatchStatus
    truth: int | None
    """The obj_id of the true object it was matched to (None for a false detection)."""


@runtime_checkable
class PerceptionViews(Protocol):
    """The perception views of an rgbd episode, for recorders that draw them."""

    def perception(self, time: float, call: PerceptionCall, boxes: Sequence[PerceivedBox]) -> None:
        """The planner API's objects after a perception call at simulated ``time`` (``boxes``)
        and the call's errors against the truth (``call``, as in the episode's record)."""


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
