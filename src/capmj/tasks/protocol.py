"""What a task is: a plain object with a seeded scene sampler, oracle goals and a success predicate.

Tasks never subclass the world.  A task object is anything with the attributes of :class:`Task`;
built-in and third-party tasks are found through the ``capmj.tasks`` entry-point group.  The
success predicate judges the *final settled state* (not a reward popped mid-episode, a defect of
the originals), and the Ravens-style matching reward computed from the oracle goals is reported
beside it for comparability only.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal, Mapping, Protocol, Sequence, runtime_checkable

import numpy as np

from capmj.errors import TaskError
from capmj.sim.objects import ObjectSpec
from capmj.sim.state import SceneState
from capmj.tasks.scene_method import scene_sampler

MAX_RESAMPLES = 1000


class Resample(Exception):
    """Raised by a task's ``sample_scene`` when this draw cannot be placed; the caller draws again
    from the same generator stream, so a seed still maps to exactly one scene."""


@dataclass(frozen=True)
class Scene:
    """A sampled episode layout.

    ``goal`` is derived from ``objects`` (never a template with stale colours); ``info`` holds the
    task's own JSON-serialisable facts (target zone id, selected block ids, initial positions…)
    that its oracle goals and success predicate need.
    """

    objects: tuple[ObjectSpec, ...]
    goal: str
    info: Mapping[str, Any] = field(default_factory=dict)

    def by_id(self, obj_id: int) -> ObjectSpec:
        for o in self.objects:
            if o.obj_id == obj_id:
                return o
        raise KeyError(obj_id)


@dataclass(frozen=True)
class Target:
    """A place an object's centre should end at; ``yaw`` is None when rotation does not matter."""

    pos: tuple[float, float, float]
    yaw: float | None = None


@dataclass(frozen=True)
class OracleGoal:
    """One Ravens-style step: ``matches[i][j] == 1`` when ``objects[i]`` may go to ``targets[j]``.

    Steps are solved in order (a stack is one step per level, bottom first).  ``replace`` lets a
    target take more than one object; otherwise assignment is one-to-one.  ``metric`` says how the
    matching reward checks a placement: ``"pose"`` (within ``tolerance`` metres of the target) or
    ``"zone"`` (centre inside the square of side ``zone_size`` around the target).
    """

    objects: tuple[int, ...]
    targets: tuple[Target, ...]
    matches: tuple[tuple[int, ...], ...]
    replace: bool = False
    rotations: bool = False
    metric: Literal["pose", "zone"] = "pose"
    tolerance: float = 0.01
    zone_size: float = 0.0

    def __post_init__(self) -> None:
        m = np.asarray(self.matches)
        if m.shape != (len(self.objects), len(self.targets)):
            raise ValueError(f"matches has shape {m.shape}, expected {(len(self.objects), len(self.targets))}")


@dataclass(frozen=True)
class Verdict:
    """The benchmark verdict on a final state.

    ``progress`` in [0, 1] is the share of the task's conditions met; ``diagnostics`` are short
    human-readable facts ("red block 3 not in green zone 7 (off by 0.034 m)") naming what failed.
    """

    success: bool
    progress: float
    diagnostics: tuple[str, ...] = ()


@runtime_checkable
class Task(Protocol):
    """The task protocol.  The docstring has three parts: Task Description / Randomizations /
    Success Conditions."""

    name: str
    tags: frozenset[str]

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        """Sample one scene from ``rng`` alone; may raise :class:`Resample`.

        Called ``generate`` before issue #28; a task that still defines only that name runs, with a
        ``DeprecationWarning`` (:mod:`capmj.tasks.scene_method`)."""
        ...

    def oracle_goals(self, scene: Scene) -> Sequence[OracleGoal]:
        """Steps that, solved in order, complete the task."""
        ...

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        """Judge a settled final state."""
        ...


def episode_rng(seed: int, stream: str = "scene") -> np.random.Generator:
    """The generator for one purpose of an episode, derived from the seed alone (no global state).

    Different ``stream`` names give independent generators, so adding randomness to one part (e.g.
    the agent) never changes the scene of a seed.
    """
    tag = int.from_bytes(stream.encode()[:8].ljust(8, b"\0"), "little")
    return np.random.default_rng(np.random.SeedSequence([int(seed), tag]))


def make_scene(task: Task, seed: int) -> Scene:
    """The scene of (task, seed): samples until the task accepts a draw, from one seeded stream.

    Raises :class:`TaskError` when the task has no usable scene method (see
    :func:`~capmj.tasks.scene_method.scene_sampler`) or places no scene in :data:`MAX_RESAMPLES` draws.
    """
    sample = scene_sampler(task)
    rng = episode_rng(seed)
    for _ in range(MAX_RESAMPLES):
        try:
            return sample(rng)
        except Resample:
            continue
    raise TaskError(f"task {task.name!r} could not place a scene for seed {seed} in {MAX_RESAMPLES} draws")
