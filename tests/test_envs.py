"""The learning-agent env: dm_env's own conformance suite, Gymnasium's checker, the bench oracle
driven through the env ends in the bench's exact final state, and a seed fixes the episode.

Images are tiny here (rendering is slow on llvmpipe); the full-size path is the same code."""

from __future__ import annotations

import subprocess
import sys
from typing import Any

import dm_env
import numpy as np
import pytest
from absl.testing import absltest
from dm_env import test_utils

from capmj.agents.oracle import OracleAgent
from capmj.envs import EnvConfig, TabletopEnv
from capmj.envs.oracle import run_oracle
from capmj.envs.tabletop import primitive_args
from capmj.errors import ConfigError
from capmj.record import NullRecorder
from capmj.runner import run_episode

SMALL = EnvConfig(width=32, height=24, robot_meshes=False, max_steps=3)


class _Conformance(test_utils.EnvironmentTestMixin):
    TASK = ""

    def make_object_under_test(self) -> TabletopEnv:
        return TabletopEnv(self.TASK, seed=10001, config=SMALL)

    def make_action_sequence(self):  # noqa: ANN201 - short: each step is a real pick-and-place
        for _ in range(3):
            yield self.make_action()


class ConformanceStackAll(_Conformance, absltest.TestCase):
    TASK = "stack-all-blocks-on-a-zone"


class ConformanceMatchingBowl(_Conformance, absltest.TestCase):
    TASK = "put-block-into-matching-bowl"


def test_gymnasium_env_checker_passes() -> None:
    gymnasium = pytest.importorskip("gymnasium")
    from gymnasium.utils.env_checker import check_env

    import capmj.envs
    from capmj.envs.gym_env import env_id

    assert env_id("stack-all-blocks-on-a-zone") in capmj.envs.register()
    env = gymnasium.make(env_id("stack-all-blocks-on-a-zone"), render_mode="rgb_array",
                         config=EnvConfig(cameras=("front",), width=32, height=24, robot_meshes=False))
    check_env(env.unwrapped, skip_render_check=True)
    obs, info = env.reset(seed=7)
    assert isinstance(obs["goal"], str) and obs["goal"] in env.observation_space["goal"]
    assert info["seed"] == 7 and obs["color"].shape == (1, 24, 32, 3)
    assert np.array_equal(env.render(), obs["color"][0])
    assert obs["objects"].shape == (32, 8) and obs["objects"][0, 0] > 0
    env.close()
    rgbd = gymnasium.make(env_id("stack-all-blocks-on-a-zone"), perception="rgbd")
    assert rgbd.unwrapped.dm_env.config.perception == "rgbd"  # the keyword reaches the dm_env
    rgbd.close()


def test_gymnasium_ids_are_registered_on_request_or_by_the_module_id_form() -> None:
    """Importing the wrapper registers nothing; ``register()`` does; so does Gymnasium's
    ``"module:env-id"`` form through :mod:`capmj.envs.gym_ids`, in a fresh process."""
    pytest.importorskip("gymnasium")
    code = ("import gymnasium, capmj.envs, capmj.envs.gym_env\n"
            "ID = 'capmj/stack-all-blocks-on-a-zone-v0'\n"
            "before = ID in gymnasium.registry\n"
            "env = gymnasium.make('capmj.envs.gym_ids:' + ID, config=capmj.envs.EnvConfig(cameras=('front',), "
            "width=16, height=12, robot_meshes=False))\n"
            "print(before, ID in gymnasium.registry, type(env.unwrapped).__name__)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["False", "True", "TabletopGymEnv"]


class _KeepWorld:
    """A recorder that keeps the bench's world (the runner attaches only non-null recorders)."""

    world: Any = None

    def attach(self, world: Any) -> None:
        self.world = world

    def __getattr__(self, name: str) -> Any:
        return getattr(NullRecorder(), name)


def test_oracle_through_env_ends_in_the_bench_final_state() -> None:
    task, seed = "stack-all-blocks-on-a-zone", 10003
    env = TabletopEnv(task, seed=seed, config=EnvConfig(cameras=()))
    first = env.reset()
    steps: list[dm_env.TimeStep] = []
    error = run_oracle(env, lambda action, ts: steps.append(ts))
    assert error is None and env.success
    assert [ts.step_type for ts in steps] == [dm_env.StepType.MID] * (len(steps) - 1) + [dm_env.StepType.LAST]
    assert steps[-1].discount == 0.0 and all(ts.discount == 1.0 for ts in steps[:-1])
    assert sum(ts.reward for ts in steps) == pytest.approx(env.progress - env.initial_progress)
    assert str(first.observation["goal"]) == env.scene.goal

    rec = _KeepWorld()
    bench = run_episode(env.task, seed, OracleAgent(), recorder=rec)
    assert bench.success and bench.primitives == len(steps)
    assert np.array_equal(rec.world.snapshot().physics, env.world.snapshot().physics)


def test_same_seed_same_episode_and_seed_sequence() -> None:
    cfg = EnvConfig(cameras=("front",), width=32, height=24, robot_meshes=False, segmentation=True, heightmap=True,
                    max_steps=2)
    runs = []
    for _ in range(2):
        env = TabletopEnv("stack-all-blocks-on-a-zone", seed=11, config=cfg, seed_stride=2)
        rng = np.random.default_rng(0)
        spec = env.action_spec()
        ts = env.reset()
        trace = [ts.observation]
        block = env.world.pose(env.world.movable_ids[0]).pos
        while not ts.last():  # a random place for the first block: a real move, then random
            action = {k: rng.uniform(s.minimum, s.maximum) for k, s in spec.items()}
            action["pick"][:3] = block
            ts = env.step(action)
            trace.append((ts.observation, ts.reward, ts.discount, env.last_result))
        runs.append(trace)
        assert env.reset().observation["goal"] is not None and env.seed == 13
        env.close()
    a, b = runs
    assert len(a) == len(b) >= 2
    for x, y in zip(a, b):
        np.testing.assert_equal(x, y)
    assert set(a[0]) == {"color", "depth", "segmentation", "heightmap", "colormap", "objects", "goal", "joint_pos",
                         "tip_pose", "suction"}
    assert a[0]["segmentation"].dtype == np.int32 and a[0]["segmentation"].max() > 0
    row, col = int((block[1] + 0.5) / 0.003125), int((block[0] - 0.25) / 0.003125)
    assert a[0]["heightmap"].shape == (320, 160)
    assert a[0]["heightmap"][row, col] == pytest.approx(2 * block[2], abs=0.005)  # the block's top


def _rows(objects: np.ndarray) -> list[tuple[int, int, int, tuple[float, ...]]]:
    """(kind, colour, size, (x, y, z)) of the present rows of an ``objects`` observation, sorted."""
    return sorted((int(r[1]), int(r[2]), int(r[3]), tuple(r[4:7])) for r in objects if r[0] > 0)


def test_rgbd_env_perceives_the_objects_and_acts_in_the_same_physics() -> None:
    """The same oracle actions in a state env and an rgbd env: bit-identical physics (perception
    only renders), and the perceived ``objects`` agree with the simulator's after every step."""
    task, seed = "stack-all-blocks-on-a-zone", 10003
    with pytest.raises(ConfigError, match="valid modes: state, rgbd"):
        EnvConfig(perception="lidar")
    traces = {}
    for mode in ("state", "rgbd"):
        env = TabletopEnv(task, seed=seed, config=EnvConfig(cameras=()), perception=mode)
        obs = [env.reset().observation["objects"]]
        assert run_oracle(env, lambda action, ts, obs=obs: obs.append(ts.observation["objects"])) is None and env.success
        traces[mode] = (obs, env.world.snapshot().physics, env.perception)
        env.close()
    (state_obs, state_phys, none), (rgbd_obs, rgbd_phys, notes) = traces["state"], traces["rgbd"]
    assert none is None and np.array_equal(state_phys, rgbd_phys)
    assert len(state_obs) == len(rgbd_obs) >= 3
    for truth, seen in zip(state_obs, rgbd_obs):
        t, p = _rows(truth), _rows(seen)
        assert [r[:3] for r in t] == [r[:3] for r in p]  # every object, right kind, colour, size
        assert max(float(np.linalg.norm(np.subtract(a[3], b[3]))) for a, b in zip(t, p)) < 0.005
    ids = [sorted(int(r[0]) for r in o if r[0] > 0) for o in rgbd_obs]
    assert all(i == ids[0] for i in ids)  # ids kept across moves (a tower hides its lower blocks)
    assert notes is not None and [c.stage for c in notes.calls][:2] == ["reset", "move 1"]
    assert len(notes.calls) == len(rgbd_obs) and not any(c.missed or c.false_detections for c in notes.calls)


def test_bad_actions_are_named() -> None:
    with pytest.raises(ConfigError, match="'pick' and 'place'"):
        primitive_args({"pick": np.zeros(4)})
    with pytest.raises(ConfigError, match="4 finite floats"):
        primitive_args({"pick": np.zeros(3), "place": np.zeros(4)})
    pick, place, yaw = primitive_args({"pick": [0.5, 0, 0, 0.3], "place": [0.6, 0.1, 0.02, 0.3]})
    assert yaw is None and place.tolist() == [0.6, 0.1, 0.02]
    assert primitive_args({"pick": [0.5, 0, 0, 0.3], "place": [0.6, 0.1, 0.02, 1.0]})[2] == 1.0
