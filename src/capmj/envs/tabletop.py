"""``TabletopEnv``: a capmj task as a ``dm_env.Environment`` in which one step is one pick-and-place.

Why it is built this way:

* **One simulation path.**  ``reset`` sets the episode up with the bench's own
  :func:`capmj.runner.start_episode` (``make_scene`` -> ``World`` -> ``settle`` ->
  :class:`EpisodeContext`), and ``step`` calls ``EpisodeContext.pick_and_place``, the budgeted
  primitive the bench's agents use.  Nothing else steps physics between two actions, so the oracle
  driven through this env ends in the bench's final state, bit for bit (tested).
* **Actions are Ravens' ``pose0``/``pose1``** as two float64 vectors ``(x, y, z, yaw)``: ``pick``
  (z and yaw are not used by the round suction cup: it descends until it touches) and ``place``
  (the gripped object's centre; the descent stops at first contact; ``yaw`` is the object's final
  yaw about z).  An action whose place yaw *equals* its pick yaw keeps the object's orientation;
  with pick yaw = the object's yaw, as the oracle gives, this is Ravens' convention that the
  object turns by ``yaw1 - yaw0``.
* **Reward** is the change of the task predicate's progress (:class:`capmj.tasks.protocol.Verdict`),
  so the rewards of an episode sum to final minus initial progress.  Discount is 1 on every step
  except a termination (success or a failed primitive), where it is 0 (dm_env's convention, so
  value bootstrapping stops); hitting the step limit is a truncation with discount 1.
* **Determinism.**  The k-th reset of ``TabletopEnv(task, seed=s)`` plays seed ``s + k * seed_stride``
  (or ``reset(seed=...)`` picks one); same seed and actions -> identical observations and rewards.
* **Costly observations are opt-in**: the three RGB-D views are on by default; segmentation and the
  top-down heightmap are off.  ``EnvConfig(cameras=())`` gives a state-only env.
* **Objects as the planner API knows them**: ``objects`` is one row per object, ``(obj_id, kind,
  colour, size, x, y, z, yaw)`` (codes: indices into :data:`OBJECT_CODES`; padded rows have obj_id
  0).  ``perception="state"`` (the default) reads them from the simulator; ``perception="rgbd"``
  from the cameras — the bench's ``--perception rgbd`` view (:mod:`capmj.agents.api.perceived`): the
  scene is perceived at reset and after every step, tracked ids survive moves, and the perception
  error is scored against the truth for the record (:attr:`TabletopEnv.perception`, never part of
  the observation).  The pick-and-place itself is the same primitive in both modes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Mapping

import dm_env
import numpy as np
from dm_env import specs

from capmj.agents.base import Budget, EpisodeContext
from capmj.errors import AgentError, BudgetExceeded, ConfigError
from capmj.perception.plugins import STATE, check_mode, load_perceiver
from capmj.records import PerceptionNotes
from capmj.runner import start_episode
from capmj.sim.motion import PrimitiveResult
from capmj.sim.objects import BLOCK_SIZES, KINDS
from capmj.sim.palette import COLOR_NAMES
from capmj.sim.robot import ARM_JOINTS
from capmj.sim.bounds import WORKSPACE
from capmj.sim.cameras import CameraRig, IMAGE_H, IMAGE_W, VIEW_CAMERAS
from capmj.sim.pose import mat_yaw
from capmj.sim.scene import HEIGHTMAP_PIXEL
from capmj.sim.world import World
from capmj.tasks.protocol import Scene, Task, Verdict

POSE_FIELDS = ("x", "y", "z", "yaw")
ACTION_LOW = np.array([WORKSPACE.xmin, WORKSPACE.ymin, WORKSPACE.zmin, -math.pi])
ACTION_HIGH = np.array([WORKSPACE.xmax, WORKSPACE.ymax, WORKSPACE.zmax, math.pi])
FAR_DEPTH = 5.0
"""Depth of pixels that see nothing (the scene's far plane, metres)."""
MAX_OBJECTS = 32
"""Rows of the ``objects`` observation (the largest scene of the built-in tasks has 17 objects)."""
OBJECT_FIELDS = ("obj_id", "kind", "color", "size", "x", "y", "z", "yaw")
OBJECT_CODES: dict[str, tuple[str, ...]] = {"kind": KINDS, "color": COLOR_NAMES, "size": tuple(BLOCK_SIZES)}
"""The codes of the ``objects`` observation's categorical columns (a size is -1 for non-blocks)."""


@dataclass(frozen=True)
class EnvConfig:
    """What the env observes and how long an episode may run.

    ``cameras`` empty -> no images at all (fastest).  ``max_steps`` None -> the task's own
    ``max_steps`` attribute if it has one, else the bench's primitive budget (:class:`Budget`).
    """

    cameras: tuple[str, ...] = VIEW_CAMERAS
    width: int = IMAGE_W
    height: int = IMAGE_H
    segmentation: bool = False
    heightmap: bool = False
    robot_meshes: bool = True
    max_steps: int | None = None
    perception: str = "state"
    """What the ``objects`` observation reads: ``state`` (the simulator), ``rgbd`` (the cameras) or
    another perceiver's name (:mod:`capmj.perception.plugins`)."""

    def __post_init__(self) -> None:
        check_mode(self.perception)
        if self.width <= 0 or self.height <= 0:
            raise ConfigError(f"image size must be positive, got {self.width}x{self.height}")
        if self.max_steps is not None and self.max_steps < 1:
            raise ConfigError(f"max_steps must be >= 1, got {self.max_steps}")
        if self.segmentation and not self.cameras:
            raise ConfigError("segmentation needs at least one camera")


def step_limit(task: Task, config: EnvConfig) -> int:
    """Pick-and-places allowed per episode (see :class:`EnvConfig`)."""
    if config.max_steps is not None:
        return int(config.max_steps)
    own = getattr(task, "max_steps", None)
    return int(own) if own else Budget().max_primitives


def primitive_args(action: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray, float | None]:
    """(pick xyz, place xyz, place yaw or None) for ``EpisodeContext.pick_and_place``."""
    if not isinstance(action, Mapping) or set(action) != {"pick", "place"}:
        raise ConfigError(f"an action is a mapping with keys 'pick' and 'place', got {action!r}")
    pick, place = (np.asarray(action[k], dtype=np.float64) for k in ("pick", "place"))
    for name, v in (("pick", pick), ("place", place)):
        if v.shape != (4,) or not np.all(np.isfinite(v)):
            raise ConfigError(f"action[{name!r}] must be 4 finite floats {POSE_FIELDS}, got {v!r}")
    return pick[:3], place[:3], None if place[3] == pick[3] else float(place[3])


class TabletopEnv(dm_env.Environment):
    """One capmj task as a dm_env environment (see the module docstring for the contract)."""

    def __init__(self, task: Task | str, seed: int = 0, *, config: EnvConfig | None = None,
                 seed_stride: int = 1, perception: str | None = None) -> None:
        if isinstance(task, str):
            from capmj.tasks.registry import get_task

            task = get_task(task)
        self.task: Task = task
        self.config = config or EnvConfig()
        if perception is not None:  # the keyword overrides the config's mode
            self.config = replace(self.config, perception=perception)
        self._seen: Any = None
        """rgbd mode: the episode's :class:`~capmj.agents.api.perceived.PerceivingContext`."""
        self._perceived: Any = None
        """rgbd mode: the episode's :class:`~capmj.agents.api.perceived.PerceivedScene`."""
        self.max_steps = step_limit(task, self.config)
        self._next_seed = int(seed)
        self._stride = int(seed_stride)
        self._rig: Any = None
        self._ctx: EpisodeContext | None = None
        self._done = True
        self.seed: int | None = None
        self.scene: Scene | None = None
        self.world: World | None = None
        self.steps = 0
        self.initial_progress = 0.0
        self.progress = 0.0
        self.verdict: Verdict | None = None
        self.last_result: PrimitiveResult | None = None
        self._obs_spec = self._make_observation_spec()

    # ------------------------------------------------------------------ specs
    def _make_observation_spec(self) -> dict[str, specs.Array]:
        c = self.config
        n, h, w = len(c.cameras), c.height, c.width
        out: dict[str, specs.Array] = {}
        if n:
            out["color"] = specs.Array((n, h, w, 3), np.uint8, "color")
            out["depth"] = specs.BoundedArray((n, h, w), np.float32, 0.0, FAR_DEPTH, "depth")
        if c.segmentation:
            out["segmentation"] = specs.Array((n, h, w), np.int32, "segmentation")
        if c.heightmap:
            rows = int(round((WORKSPACE.ymax - WORKSPACE.ymin) / HEIGHTMAP_PIXEL))
            cols = int(round((WORKSPACE.xmax - WORKSPACE.xmin) / HEIGHTMAP_PIXEL))
            out["heightmap"] = specs.BoundedArray((rows, cols), np.float32, 0.0, FAR_DEPTH, "heightmap")
            out["colormap"] = specs.Array((rows, cols, 3), np.uint8, "colormap")
        out["objects"] = specs.Array((MAX_OBJECTS, len(OBJECT_FIELDS)), np.float64, "objects")
        out["goal"] = specs.StringArray((), name="goal")
        out["joint_pos"] = specs.Array((len(ARM_JOINTS),), np.float64, "joint_pos")
        out["tip_pose"] = specs.Array((4,), np.float64, "tip_pose")
        out["suction"] = specs.BoundedArray((1,), np.float64, 0.0, 1.0, "suction")
        return out

    def observation_spec(self) -> dict[str, specs.Array]:
        return dict(self._obs_spec)

    def action_spec(self) -> dict[str, specs.BoundedArray]:
        return {k: specs.BoundedArray((4,), np.float64, ACTION_LOW, ACTION_HIGH, k) for k in ("pick", "place")}

    def reward_spec(self) -> specs.Array:
        return specs.Array((), np.float64, "reward")

    def discount_spec(self) -> specs.BoundedArray:
        return specs.BoundedArray((), np.float64, 0.0, 1.0, "discount")

    # ------------------------------------------------------------------ episode
    def reset(self, seed: int | None = None) -> dm_env.TimeStep:
        """Start the episode of ``seed`` (default: the next seed of this env's sequence)."""
        if seed is None:
            seed, self._next_seed = self._next_seed, self._next_seed + self._stride
        else:
            self._next_seed = int(seed) + self._stride
        self.close()
        self.seed = int(seed)
        self._ctx = start_episode(self.task, self.seed, budget=Budget(max_primitives=self.max_steps))
        self.scene, self.world = self._ctx.scene, self._ctx.world
        if self.config.perception != STATE:
            from capmj.agents.api.perceived import PerceivedScene, PerceivingContext
            from capmj.agents.api.perception_audit import PerceptionAudit

            audit = PerceptionAudit(self._ctx, self.config.perception)
            self._perceived = PerceivedScene(self.world, load_perceiver(self.config.perception), observer=audit.observe)
            self._seen = PerceivingContext(self._ctx, self._perceived, audit)
        self.steps, self._done, self.last_result = 0, False, None
        self.verdict = self.task.evaluate(self.scene, self.world.state())
        self.initial_progress = self.progress = float(self.verdict.progress)
        return dm_env.restart(self._observe())

    def step(self, action: Mapping[str, Any]) -> dm_env.TimeStep:
        if self._done or self._ctx is None:
            return self.reset()
        pick, place, yaw = primitive_args(action)
        try:
            acting = self._seen if self._seen is not None else self._ctx  # rgbd: perceive again after it
            res: PrimitiveResult | None = acting.pick_and_place(pick, place, yaw)
        except BudgetExceeded:  # the simulation-step budget: the episode is cut off (truncation)
            res = None
        self.last_result = res
        self.steps += 1
        failed = res is not None and not res.ok
        verdict = self.task.evaluate(self.scene, self.world.state())  # type: ignore[union-attr,arg-type]
        ended = verdict.success or failed or res is None or self.steps >= self.max_steps
        if ended:
            verdict = self._ctx.verdict()  # the bench's final settle-and-judge
            self._done = True
        self.verdict = verdict
        reward = float(verdict.progress) - self.progress
        self.progress = float(verdict.progress)
        obs = self._observe()
        if not ended:
            return dm_env.transition(reward, obs, 1.0)
        if verdict.success or failed:
            return dm_env.termination(reward, obs)
        return dm_env.truncation(reward, obs, 1.0)

    @property
    def camera_rig(self) -> Any:
        """The :class:`~capmj.sim.cameras.CameraRig` of the current episode (None before rendering)."""
        return self._rig

    @property
    def ended(self) -> bool:
        """Whether the current episode is over (the next ``step`` starts a new one)."""
        return self._done

    @property
    def success(self) -> bool:
        return bool(self.verdict is not None and self.verdict.success)

    @property
    def perception(self) -> PerceptionNotes | None:
        """rgbd mode: the episode's perception error so far, scored against the truth (None in state mode)."""
        notes = self._ctx.notes.get("perception") if self._ctx is not None else None
        return notes if isinstance(notes, PerceptionNotes) else None

    def close(self) -> None:
        if self._rig is not None:
            self._rig.close()
            self._rig = None
        if self._perceived is not None:
            self._perceived.close()
            self._seen = self._perceived = None

    # ------------------------------------------------------------------ observing
    def _observe(self) -> dict[str, np.ndarray]:
        w, c = self.world, self.config
        assert w is not None and self.scene is not None
        obs: dict[str, np.ndarray] = {}
        if c.cameras or c.heightmap:
            if self._rig is None:
                self._rig = CameraRig(w, width=c.width, height=c.height, robot_meshes=c.robot_meshes)
        if c.cameras:
            frames = [self._rig.render(name) for name in c.cameras]
            obs["color"] = np.stack([f.rgb for f in frames])
            obs["depth"] = np.minimum(np.stack([f.depth for f in frames]), np.float32(FAR_DEPTH))
            if c.segmentation:
                obs["segmentation"] = np.stack([f.seg for f in frames])
        if c.heightmap:
            hm = self._rig.heightmap()
            obs["heightmap"] = np.minimum(np.array(hm.height), np.float32(FAR_DEPTH))
            obs["colormap"] = np.array(hm.colormap)
        obs["objects"] = self._objects()
        obs["goal"] = np.array(self.scene.goal, dtype=object)
        obs["joint_pos"] = w.arm_q()
        pos, rot = w.tip_pose()
        obs["tip_pose"] = np.array([pos[0], pos[1], pos[2], mat_yaw(rot)])
        obs["suction"] = np.array([0.0 if w.suction.held is None else 1.0])
        return obs

    def _objects(self) -> np.ndarray:
        """The ``objects`` observation: from the simulator, or the latest perception (rgbd)."""
        w = self.world
        assert w is not None
        out = np.zeros((MAX_OBJECTS, len(OBJECT_FIELDS)))
        if self._perceived is not None:
            seen = self._perceived
            rows = [(o, seen.pose(o.obj_id)) for o in seen.objects]
        else:
            rows = [(o, w.pose(o.obj_id)) for o in w.objects]
        for i, (o, pose) in enumerate(rows[:MAX_OBJECTS]):
            size = OBJECT_CODES["size"].index(o.size) if o.size in OBJECT_CODES["size"] else -1
            out[i] = (o.obj_id, KINDS.index(o.kind), COLOR_NAMES.index(o.color), size, *pose.pos, pose.yaw)
        return out

    # ------------------------------------------------------------------ helpers for policies
    def oracle_action(self, pick: Any, place: Any, place_yaw: float | None = None) -> dict[str, np.ndarray]:
        """The env action for a primitive call ``(pick, place, place_yaw)`` as agents make it.

        The pick yaw is the yaw of the movable object nearest the pick point (Ravens' ``pose0``);
        ``place_yaw`` None keeps the object's orientation (place yaw = pick yaw).  Values are
        clipped to the action bounds (an object knocked off the workspace is picked at its edge).
        """
        w = self.world
        if w is None:
            raise AgentError("oracle_action needs a reset env")
        pick3 = np.zeros(3)
        pick3[: len(pick)] = np.asarray(pick, float)[:3]
        place3 = np.zeros(3)
        place3[: len(place)] = np.asarray(place, float)[:3]
        near = min(w.movable_ids, default=None,
                   key=lambda i: float(np.hypot(*(np.asarray(w.pose(i).pos[:2]) - pick3[:2]))))
        yaw0 = w.pose(near).yaw if near is not None else 0.0
        yaw1 = yaw0 if place_yaw is None else (place_yaw + math.pi) % (2 * math.pi) - math.pi
        lo, hi = ACTION_LOW, ACTION_HIGH
        return {"pick": np.clip(np.append(pick3, yaw0), lo, hi), "place": np.clip(np.append(place3, yaw1), lo, hi)}
