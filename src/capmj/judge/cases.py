"""One labelled final state (:class:`JudgeCase`) and how it is put into a MuJoCo world.

A case stores the *layout* it was made from (the poses of the movable objects, before the final
settle), not the settled result: the set builder and the judge both realise it the same way —
the episode's scene, its initial settle, the layout placed at rest, :data:`JUDGE_SETTLE_STEPS` of
settling — so MuJoCo's deterministic stepping gives them the very same state, and the label the
builder computed with the task predicate is the label of the state the reporter is shown.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass
from typing import Any, Mapping

from capmj.agents.base import JUDGE_SETTLE_STEPS, EpisodeContext
from capmj.record import Recorder
from capmj.runner import start_episode
from capmj.sim.state import Pose, SceneState
from capmj.sim.world import World, WorldSnapshot
from capmj.tasks.protocol import Scene, Task, Verdict

__all__ = ["HARD_KINDS", "KINDS", "NEGATIVE_KINDS", "JudgeCase", "Stage", "layout_of", "set_digest"]

NEGATIVE_KINDS: tuple[str, ...] = ("displaced", "unstacked", "toppled", "swapped", "wrong_bowl", "toppled_out")
"""Perturbations that break one success condition (see :mod:`capmj.judge.perturb`); ``toppled_out``,
made only where a tower has no room to lie where it stood, breaks two (the stack and the placement)."""
HARD_KINDS: tuple[str, ...] = ("near_inside", "near_outside")
"""One object moved to just inside (label True) or just outside (label False) its tolerance."""
KINDS: tuple[str, ...] = ("oracle", *NEGATIVE_KINDS, *HARD_KINDS)
"""Every kind of case; ``oracle`` is the oracle's final state (label True)."""

Layout = dict[int, Pose]
"""Poses of the movable objects by id."""


@dataclass(frozen=True)
class JudgeCase:
    """A final state with its ground-truth label.

    ``label`` is the task predicate's success on the realised state (checked when the set is
    built: a negative that still passes, or a hard-inside case that fails, is never kept);
    ``condition`` is what the predicate says is wrong (its diagnostics, empty for positives);
    ``detail`` says what the perturbation did.  ``layout`` holds ``(obj_id, x, y, z, qw, qx, qy, qz)``
    of every movable object.
    """

    task: str
    seed: int
    case: str
    kind: str
    label: bool
    condition: str
    detail: str
    progress: float
    layout: tuple[tuple[float, ...], ...]

    @property
    def key(self) -> str:
        """Unique name of the case in a set: ``task/seed/case``."""
        return f"{self.task}/{self.seed}/{self.case}"

    def poses(self) -> Layout:
        return {int(row[0]): Pose.of(row[1:4], row[4:8]) for row in self.layout}

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["layout"] = [list(row) for row in self.layout]
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> JudgeCase:
        return cls(str(d["task"]), int(d["seed"]), str(d["case"]), str(d["kind"]), bool(d["label"]),
                   str(d["condition"]), str(d["detail"]), float(d["progress"]),
                   tuple(tuple(float(v) for v in row) for row in d["layout"]))


def layout_rows(layout: Mapping[int, Pose]) -> tuple[tuple[float, ...], ...]:
    """A layout as sorted ``(id, x, y, z, qw, qx, qy, qz)`` rows rounded to 1e-9 (stable JSON)."""
    return tuple((float(i), *(round(float(v), 9) for v in (*p.pos, *p.quat))) for i, p in sorted(layout.items()))


def layout_of(state: SceneState, movable: tuple[int, ...]) -> Layout:
    """The poses of the movable objects of a state."""
    return {i: state.poses[i] for i in movable}


def set_digest(cases: list[JudgeCase]) -> str:
    """SHA-256 of the set's canonical JSON: equal digests mean byte-identical sets."""
    text = json.dumps([c.to_dict() for c in cases], sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


class Stage:
    """The world of one (task, seed), reusable for any number of layouts.

    Set up as every episode is (:func:`capmj.runner.start_episode`: scene of the seed, compiled
    world, initial settle); the initial state is snapshotted, and :meth:`realise` returns to it
    before placing a layout, which is the same physics as a fresh world (MuJoCo restores the full
    integration state).
    """

    def __init__(self, task: Task, seed: int) -> None:
        self.task = task
        self.seed = seed
        start = start_episode(task, seed)
        self.scene: Scene = start.scene
        self.world: World = start.world
        self.initial: WorldSnapshot = self.world.snapshot()

    def context(self, recorder: Recorder | None = None) -> EpisodeContext:
        """A fresh agent's context over the world as it is now (after :meth:`restart`: the
        episode's start), as an agent or a reporter gets it."""
        return EpisodeContext(self.task, self.seed, self.scene, self.world, recorder=recorder)

    def restart(self) -> None:
        """Back to the episode's initial state (arm at home, objects at their spawn poses)."""
        self.world.restore(self.initial)

    def realise(self, layout: Mapping[int, Pose]) -> SceneState:
        """Place ``layout`` on the initial world at rest, settle, return the state."""
        self.restart()
        return self.place(layout)

    def place(self, layout: Mapping[int, Pose]) -> SceneState:
        """Place ``layout`` on the world as it is now (after :meth:`restart`: the initial world,
        e.g. once a VLM reporter has taken its "before" image), settle, return the state."""
        self.world.place_objects(layout)
        self.world.settle(max_steps=JUDGE_SETTLE_STEPS)
        return self.world.state()

    def evaluate(self, state: SceneState) -> Verdict:
        return self.task.evaluate(self.scene, state)
