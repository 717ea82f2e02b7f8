"""Collect oracle demonstrations: the bench oracle driven through :class:`TabletopEnv`.

Workers are processes on the ``spawn`` context (MuJoCo/EGL do not survive ``fork`` after GL
initialisation), as in the bench.  A worker writes one seed's files into ``.partial/<seed>/`` and
the parent renames finished episodes into place *in seed order*, so episode numbers, file names and
bytes do not depend on the number of workers or on scheduling.  A killed run loses only episodes
in flight; running again continues after the last seed tried (Ravens' ``max_seed`` rule).
"""

from __future__ import annotations

import json
import os
import pickle
import shutil
import time
from collections import deque
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass, field
from multiprocessing import get_context
from pathlib import Path
from typing import Any, Callable

import numpy as np

from capmj.demos.dataset import (FIELDS, PICKLE_PROTOCOL, camera_configs, dataset_dir, ravens_action,
                                 resume_point, split_seeds, write_episode)
from capmj.envs.oracle import run_oracle
from capmj.envs.tabletop import EnvConfig, TabletopEnv
from capmj.tasks.protocol import Task

MP_CONTEXT = "spawn"
PARTIAL_NAME = "episode.pkl"


@dataclass(frozen=True)
class EpisodeOutcome:
    """What a worker reports for one seed (the arrays stay in its ``.partial`` folder)."""

    task: str
    seed: int
    success: bool
    steps: int
    error: str | None
    wall_s: float


@dataclass
class SplitStats:
    """Totals of one ``<task>-<split>`` directory after a run (printed as JSON by the CLI)."""

    task: str
    split: str
    path: str
    saved: int = 0
    skipped: int = 0
    steps: int = 0
    bytes: int = 0
    wall_s: float = 0.0
    resumed_from: int = 0
    errors: list[str] = field(default_factory=list)

    @property
    def bytes_per_step(self) -> float:
        return self.bytes / self.steps if self.steps else 0.0

    def to_dict(self) -> dict[str, Any]:
        d = {k: getattr(self, k) for k in ("task", "split", "path", "saved", "skipped", "steps", "bytes",
                                            "wall_s", "resumed_from")}
        d["bytes_per_step"] = round(self.bytes_per_step, 1)
        d["errors"] = self.errors[:10]
        return d


def _info(env: TabletopEnv) -> dict[str, Any]:
    w = env.world
    assert w is not None
    res = env.last_result
    poses = {}
    for o in w.objects:
        p = w.pose(o.obj_id)
        poses[o.obj_id] = (tuple(float(v) for v in p.pos), tuple(float(v) for v in p.quat_xyzw))
    return {"lang_goal": env.scene.goal if env.scene else "", "task": env.task.name, "seed": env.seed,
            "step": env.steps, "progress": env.progress, "success": env.success,
            "status": None if res is None else res.status, "poses": poses}


def demonstrate(task: Task | str, seed: int, config: EnvConfig) -> tuple[EpisodeOutcome, dict[str, Any]]:
    """Run the oracle on (task, seed) through the env; the Ravens fields of the episode."""
    t0 = time.perf_counter()
    env = TabletopEnv(task, seed=seed, config=config)
    try:
        ts = env.reset()
        obs, rewards, infos = [ts.observation], [0.0], [_info(env)]
        actions: list[dict[str, tuple[tuple[float, ...], tuple[float, ...]]] | None] = []  # None: no action after the last step

        def on_step(action: dict[str, np.ndarray], step: Any) -> None:
            actions.append(ravens_action(action))
            obs.append(step.observation)
            rewards.append(float(step.reward))
            infos.append(_info(env))

        error = run_oracle(env, on_step)
        actions.append(None)
        record = {"color": np.stack([o["color"] for o in obs]).astype(np.uint8),
                  "depth": np.stack([o["depth"] for o in obs]).astype(np.float32),
                  "action": actions, "reward": rewards, "info": infos}
        if env.camera_rig is not None:
            record["cameras"] = camera_configs(env.camera_rig, config.cameras)
        out = EpisodeOutcome(env.task.name, seed, error is None, len(actions) - 1, error, time.perf_counter() - t0)
        return out, record
    finally:
        env.close()


def _job(task: Task | str, seed: int, config: EnvConfig, partial: str) -> EpisodeOutcome:
    """Worker entry: record one seed into ``partial/<seed>/`` (a failure becomes an outcome)."""
    try:
        outcome, record = demonstrate(task, seed, config)
    except Exception as exc:  # noqa: BLE001 - one seed's crash must not end the run
        return EpisodeOutcome(getattr(task, "name", str(task)), seed, False, 0, f"{type(exc).__name__}: {exc}", 0.0)
    if outcome.success:  # written in final form once; the parent only renames
        target = Path(partial) / str(seed)
        cams = record.pop("cameras", None)
        write_episode(target, PARTIAL_NAME, record)
        if cams is not None:
            with open(target / "cameras.pkl", "wb") as fh:
                pickle.dump(cams, fh, protocol=PICKLE_PROTOCOL)
    return outcome


def collect_split(task: Task | str, split: str, n: int, out: Path | str, *, config: EnvConfig,
                   workers: int = 1, progress: Callable[[int], None] | None = None,
                   pool: ProcessPoolExecutor | None = None) -> SplitStats:
    """Save ``n`` successful oracle episodes of ``task`` for ``split`` under ``out`` (resuming).

    ``task`` is a name (workers find it through the entry points) or a task object (pickled to the
    workers: how a task added with ``registry.register`` reaches them).
    """
    name = task if isinstance(task, str) else task.name
    directory = dataset_dir(out, name, split)
    directory.mkdir(parents=True, exist_ok=True)
    partial = directory / ".partial"
    shutil.rmtree(partial, ignore_errors=True)
    saved, last_seed = resume_point(directory)
    stats = SplitStats(name, split, str(directory), saved=saved, resumed_from=saved)
    t0 = time.perf_counter()
    seeds = split_seeds(split, last_seed)
    window: deque[tuple[int, Future[EpisodeOutcome] | EpisodeOutcome]] = deque()
    in_flight = max(1, workers) * 2 if pool is not None else 1

    def submit() -> None:
        seed = next(seeds)
        if pool is None:
            window.append((seed, _job(task, seed, config, str(partial))))
        else:
            window.append((seed, pool.submit(_job, task, seed, config, str(partial))))

    while stats.saved < n:
        while len(window) < min(in_flight, max(1, n - stats.saved)) or not window:
            submit()
        seed, fut = window.popleft()
        outcome = fut.result() if isinstance(fut, Future) else fut
        _store(directory, partial, outcome, stats)
        if progress is not None and outcome.success:
            progress(1)
    for _, fut in window:  # seeds beyond n started speculatively: drop them
        if isinstance(fut, Future):
            fut.cancel()
            if not fut.cancelled():
                fut.result()
    shutil.rmtree(partial, ignore_errors=True)
    stats.wall_s = round(time.perf_counter() - t0, 3)
    return stats


def _store(directory: Path, partial: Path, outcome: EpisodeOutcome, stats: SplitStats) -> None:
    if not outcome.success:
        stats.skipped += 1
        stats.errors.append(f"seed {outcome.seed}: {outcome.error}")
        with open(directory / "skipped.jsonl", "a") as fh:
            fh.write(json.dumps({"seed": outcome.seed, "error": outcome.error}) + "\n")
        return
    src = partial / str(outcome.seed)
    if (src / "cameras.pkl").exists() and not (directory / "cameras.pkl").exists():
        os.replace(src / "cameras.pkl", directory / "cameras.pkl")
    name = f"{stats.saved:06d}-{outcome.seed}.pkl"
    for field_name in FIELDS:  # action/ last: it is the index the loaders scan
        (directory / field_name).mkdir(exist_ok=True)
        os.replace(src / field_name / PARTIAL_NAME, directory / field_name / name)
        stats.bytes += (directory / field_name / name).stat().st_size
    stats.steps += outcome.steps
    stats.saved += 1
    shutil.rmtree(src, ignore_errors=True)


def make_pool(workers: int) -> ProcessPoolExecutor | None:
    """A spawn-context pool for ``workers > 1``; None means in-process."""
    if workers <= 1:
        return None
    return ProcessPoolExecutor(max_workers=workers, mp_context=get_context(MP_CONTEXT))
