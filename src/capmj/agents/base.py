"""What an agent gets during an episode, and what it must provide.

An agent acts through :class:`EpisodeContext` only: it counts primitives against a step budget,
forwards every primitive to the recorder, and can reset the world to the episode's initial state
(for re-planning).  Budgets are in primitives and simulation steps, never wall-clock.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Protocol

import numpy as np

from capmj.errors import BudgetExceeded
from capmj.record import NullRecorder, Recorder
from capmj.sim.motion import PrimitiveResult
from capmj.sim.primitives import Primitives
from capmj.sim.world import World, WorldSnapshot
from capmj.tasks.protocol import Scene, Task, Verdict


JUDGE_SETTLE_STEPS = 1000
"""Most physics steps (2 s simulated at the 2 ms step) to let objects come to rest before a final
state is judged or shown to a reporter.  A pick-and-place already ends with a looser settle (at most
750 steps, to 0.01 m/s), so this, at ``World.settle``'s 0.005 m/s, only catches what is still
rocking or rolling (a ball, a block knocked off a stack); it is shorter than the 1500-step settle
of a freshly spawned scene, and ``World.settle`` stops as soon as everything is that slow."""


@dataclass(frozen=True)
class Budget:
    """Per-attempt limits: pick-and-place calls, simulation steps, and characters of the messages
    a plan records with ``say`` (they are kept in the episode's record)."""

    max_primitives: int = 40
    max_sim_steps: int = 150_000  # 300 s of simulated time
    max_said_chars: int = 100_000


@dataclass(frozen=True)
class Checkpoint:
    """The world and the attempt's placements at one moment (see :meth:`EpisodeContext.checkpoint`)."""

    world: WorldSnapshot
    placements: dict[int, tuple[Any, Any]]


class EpisodeContext:
    """The live episode as agents see it (the LLM planner sees a narrower facade on top)."""

    def __init__(self, task: Task, seed: int, scene: Scene, world: World, *, budget: Budget | None = None,
                 recorder: Recorder | None = None) -> None:
        self.task = task
        self.seed = seed
        self.scene = scene
        self.world = world
        self.arm = Primitives(world)  # the pick-and-place primitive over this world
        self.budget = budget or Budget()
        self.recorder: Recorder = recorder or NullRecorder()
        self.attempt_primitives = 0   # pick-and-places in the current attempt
        self.total_primitives = 0     # over all attempts
        self.attempt = 0
        self._initial = world.snapshot()
        self._attempt_steps0 = world.steps
        self.notes: dict[str, Any] = {}
        self.placements: dict[int, tuple[Any, Any]] = {}  # obj_id -> (target, pos after), this attempt

    # ------------------------------------------------------------------ acting
    def pick_and_place(self, pick: np.ndarray, place: np.ndarray, place_yaw: float | None = None) -> PrimitiveResult:
        """One budgeted, recorded pick-and-place.  Raises ``BudgetExceeded`` when out of budget."""
        self.check_budget()
        res = self.arm.pick_and_place(np.asarray(pick, float), np.asarray(place, float), place_yaw)
        if res.ok and res.obj_id is not None:
            self.placements[res.obj_id] = (res.place, res.final_pos)
        self.count_primitive(asdict(res))
        return res

    def check_budget(self, max_primitives: int | None = None, unit: str = "pick-and-places") -> None:
        """Raise ``BudgetExceeded`` when the attempt has used ``max_primitives`` primitives (default
        ``Budget.max_primitives``; ``unit`` names them in the message) or its simulation steps."""
        limit = self.budget.max_primitives if max_primitives is None else max_primitives
        if self.attempt_primitives >= limit:
            raise BudgetExceeded(f"primitive budget of {limit} {unit} used up")
        if self.world.steps - self._attempt_steps0 >= self.budget.max_sim_steps:
            raise BudgetExceeded(f"simulation budget of {self.budget.max_sim_steps} steps used up")

    def count_primitive(self, info: dict[str, Any]) -> None:
        """One primitive done (a pick-and-place, or a move of the low-level API): counted in this
        attempt and the episode, and sent to the recorder with the attempt number."""
        self.attempt_primitives += 1
        self.total_primitives += 1
        info["attempt"] = self.attempt
        self.recorder.primitive(self.total_primitives, self.world.time, info)

    def reset(self) -> None:
        """Restore the episode's initial state (before a re-plan)."""
        self.world.restore(self._initial)
        self.arm = Primitives(self.world, self.arm.cfg)  # motion state must match the restored arm
        self.attempt += 1
        self.attempt_primitives = 0
        self.placements = {}
        self._attempt_steps0 = self.world.steps

    def reset_scene(self) -> None:
        """Restore the episode's initial scene *within* the current attempt: a plan's ``reset()``
        (CapRavens' plans reset and retried after their own failed check).

        The world returns to exactly the state :meth:`reset` returns to: the settled initial scene
        physics produced, not a pose anyone invented.  Unlike :meth:`reset` it opens no new attempt
        and refunds nothing: the pick-and-places and simulation steps spent before still count
        against the attempt's budgets (the world's step counter goes back with the state), so a
        plan cannot reset its way past them."""
        spent = self.world.steps - self._attempt_steps0
        self.world.restore(self._initial)
        self.arm = Primitives(self.world, self.arm.cfg)
        self.placements = {}
        self._attempt_steps0 = self.world.steps - spent

    def next_attempt(self) -> None:
        """Start a new attempt from the state the last one left (a re-plan that keeps the scene,
        the ``careful`` loop's partial re-plan): budgets count afresh, nothing is restored."""
        self.attempt += 1
        self.attempt_primitives = 0
        self._attempt_steps0 = self.world.steps

    def checkpoint(self) -> Checkpoint:
        """The state at the end of an attempt, to return to with :meth:`restore`."""
        return Checkpoint(self.world.snapshot(), dict(self.placements))

    def restore(self, checkpoint: Checkpoint) -> None:
        """Return to the end of an earlier attempt, within the current one (no primitive is counted):
        an attempt whose plan is identical to that attempt's is not run again but ends where it did."""
        self.world.restore(checkpoint.world)
        self.arm = Primitives(self.world, self.arm.cfg)
        self.placements = dict(checkpoint.placements)
        self._attempt_steps0 = self.world.steps

    # ------------------------------------------------------------------ judging
    def verdict(self) -> Verdict:
        """Let objects settle, then judge the final state with the task's predicate."""
        self.world.settle(max_steps=JUDGE_SETTLE_STEPS)
        return self.task.evaluate(self.scene, self.world.state())


class Agent(Protocol):
    """An agent solves one episode by acting on the context; exceptions are recorded, not fatal."""

    name: str

    @property
    def model(self) -> str | None:
        """The LLM model string, None for non-LLM agents."""

    def act(self, ctx: EpisodeContext) -> None:
        ...
