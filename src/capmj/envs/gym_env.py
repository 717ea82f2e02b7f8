"""Gymnasium view of :class:`TabletopEnv` (``pip install capmj[gym]``).

:func:`register_all` (also ``capmj.envs.register()``) registers one id per installed task,
``capmj/<task>-v0`` (task names come from entry-point metadata, no plugin is imported); importing
this module registers nothing.  So either::

    import capmj.envs
    capmj.envs.register()
    env = gymnasium.make("capmj/stack-all-blocks-on-a-zone-v0", config=EnvConfig(width=160, height=120))

or, in Gymnasium's ``"module:env-id"`` form, ``gymnasium.make("capmj.envs.gym_ids:capmj/stack-all-blocks-on-a-zone-v0")``
(:mod:`capmj.envs.gym_ids` is the one module whose import registers: that is what the form asks
of a module; Gymnasium 1.x has no entry-point mechanism for environment plugins).
``perception="rgbd"`` (``gymnasium.make(..., perception="rgbd")``) fills the ``objects``
observation from the cameras instead of the simulator (:class:`TabletopEnv`).

Spaces mirror the dm_env specs: a ``Dict`` of ``Box`` (images, depth, proprioception) and ``Text``
(the goal); the action is ``Dict(pick=Box(4), place=Box(4))`` of ``(x, y, z, yaw)``.
``reset(seed=s)`` plays seed ``s``; ``reset()`` plays the next seed.  ``terminated`` means success or
a failed primitive, ``truncated`` the step limit.
"""

from __future__ import annotations

import string
from typing import Any

try:
    import gymnasium as gym
    from gymnasium import spaces
except ImportError as exc:  # pragma: no cover - depends on the install
    from capmj.errors import ConfigError

    raise ConfigError("the Gymnasium wrapper needs the 'gym' extra: pip install 'capmj[gym]'") from exc
import numpy as np
from dm_env import specs

from capmj.envs.tabletop import EnvConfig, TabletopEnv
from capmj.tasks.protocol import Task

GOAL_CHARSET = string.printable
GOAL_MAX_LENGTH = 1000
ID_PREFIX = "capmj/"
VERSION = "v0"


def env_id(task_name: str) -> str:
    """The Gymnasium id of a task, e.g. ``capmj/stack-all-blocks-on-a-zone-v0``."""
    return f"{ID_PREFIX}{task_name}-{VERSION}"


def to_space(spec: specs.Array) -> spaces.Space:
    """The Gymnasium space of one dm_env spec."""
    if isinstance(spec, specs.StringArray):
        return spaces.Text(max_length=GOAL_MAX_LENGTH, min_length=0, charset=GOAL_CHARSET)
    dtype = np.dtype(spec.dtype)
    if isinstance(spec, specs.BoundedArray):
        low = np.broadcast_to(spec.minimum, spec.shape).astype(dtype)
        high = np.broadcast_to(spec.maximum, spec.shape).astype(dtype)
    elif np.issubdtype(dtype, np.integer):
        info = np.iinfo(dtype)
        low, high = np.full(spec.shape, info.min, dtype), np.full(spec.shape, info.max, dtype)
    else:
        low, high = np.full(spec.shape, -np.inf, dtype), np.full(spec.shape, np.inf, dtype)
    return spaces.Box(low=low, high=high, shape=spec.shape, dtype=dtype)


class TabletopGymEnv(gym.Env):
    """A Gymnasium ``Env`` over :class:`TabletopEnv`; ``env.dm_env`` is the wrapped environment."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 1}  # one frame per pick-and-place

    def __init__(self, task: Task | str, config: EnvConfig | None = None, seed: int = 0,
                 render_mode: str | None = None, perception: str | None = None) -> None:
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.dm_env = TabletopEnv(task, seed=seed, config=config, perception=perception)
        self.render_mode = render_mode
        self.observation_space = spaces.Dict({k: to_space(s) for k, s in self.dm_env.observation_spec().items()})
        self.action_space = spaces.Dict({k: to_space(s) for k, s in self.dm_env.action_spec().items()})
        self._last_obs: dict[str, Any] | None = None

    def _obs(self, observation: dict[str, Any]) -> dict[str, Any]:
        out = dict(observation)
        out["goal"] = str(observation["goal"])
        self._last_obs = out
        return out

    def _info(self) -> dict[str, Any]:
        e = self.dm_env
        res = e.last_result
        return {"seed": e.seed, "progress": e.progress, "success": e.success, "steps": e.steps,
                "status": None if res is None else res.status, "message": "" if res is None else res.message}

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, Any], dict[str, Any]]:
        super().reset(seed=seed)
        ts = self.dm_env.reset(seed=seed)
        return self._obs(ts.observation), self._info()

    def step(self, action: dict[str, Any]) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        if self.dm_env.ended:
            raise RuntimeError("the episode is over; call reset() before step()")
        ts = self.dm_env.step(action)
        terminated = bool(ts.last() and ts.discount == 0.0)
        truncated = bool(ts.last() and not terminated)
        return self._obs(ts.observation), float(ts.reward), terminated, truncated, self._info()

    def render(self) -> np.ndarray | None:
        """``rgb_array``: the first camera's colour image of the last observation."""
        if self.render_mode != "rgb_array" or self._last_obs is None or "color" not in self._last_obs:
            return None
        return np.asarray(self._last_obs["color"][0])

    def close(self) -> None:
        self.dm_env.close()


def register_all() -> list[str]:
    """Register ``capmj/<task>-v0`` for every installed task (idempotent); returns the ids."""
    from capmj.tasks.registry import list_tasks

    ids = []
    for info in list_tasks():
        eid = env_id(info.name)
        if eid not in gym.registry:
            gym.register(id=eid, entry_point=f"{__name__}:TabletopGymEnv", kwargs={"task": info.name})
        ids.append(eid)
    return ids

