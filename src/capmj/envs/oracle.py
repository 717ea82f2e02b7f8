"""The bench's oracle as a policy of :class:`TabletopEnv`: every pick-and-place it decides on goes
through ``env.step``, so demonstrations and the oracle-equivalence test exercise the env's own path.

:class:`~capmj.agents.oracle.OracleAgent` is written against :class:`EpisodeContext` and reads only
``task``, ``scene``, ``world``, ``notes`` and ``pick_and_place``; :class:`_ThroughEnv` offers those
with ``pick_and_place`` turned into an env action (:meth:`TabletopEnv.oracle_action`).  No second
oracle exists, so a fix to the bench's oracle reaches the demonstrations too.
"""

from __future__ import annotations

from typing import Any, Callable

import dm_env
import numpy as np

from capmj.agents.oracle import OracleAgent
from capmj.envs.tabletop import TabletopEnv
from capmj.errors import AgentError, BudgetExceeded
from capmj.sim.motion import PrimitiveResult

StepHook = Callable[[dict[str, np.ndarray], dm_env.TimeStep], None]
"""Called after each env step with the action taken and the time step it returned."""


class _ThroughEnv:
    def __init__(self, env: TabletopEnv, on_step: StepHook | None) -> None:
        self.env = env
        self.task, self.scene, self.world, self.seed = env.task, env.scene, env.world, env.seed
        self.notes: dict[str, Any] = {}
        self._on_step = on_step

    def pick_and_place(self, pick: Any, place: Any, place_yaw: float | None = None) -> PrimitiveResult:
        if self.env.ended:
            raise AgentError(f"the episode ended after {self.env.steps} steps but the oracle wants another move")
        action = self.env.oracle_action(pick, place, place_yaw)
        ts = self.env.step(action)
        if self._on_step is not None:
            self._on_step(action, ts)
        if self.env.last_result is None:
            raise BudgetExceeded("simulation-step budget used up")
        return self.env.last_result


def run_oracle(env: TabletopEnv, on_step: StepHook | None = None) -> str | None:
    """Solve the env's current (freshly reset) episode with the oracle, step by step.

    Returns None when the episode ended in success, else why not ("AgentError: ..." when the
    oracle itself gave up).  The env is left at the episode's final state.
    """
    if env.world is None or env.ended or env.steps:
        raise AgentError("run_oracle needs an env that was just reset")
    try:
        OracleAgent().act(_ThroughEnv(env, on_step))  # type: ignore[arg-type]
    except Exception as exc:  # noqa: BLE001 - recorded as this episode's failure
        return f"{type(exc).__name__}: {exc}"
    if env.success:
        return None
    if not env.ended:
        return f"oracle finished after {env.steps} steps without reaching success (progress {env.progress:.2f})"
    return f"episode ended without success (progress {env.progress:.2f})"
