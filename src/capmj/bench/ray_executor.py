"""``--executor ray``: the grid's episodes on a Ray cluster, one actor per worker.

Why actors, not one Ray task per episode: a fresh Ray worker pays the same seconds of importing
litellm and MuJoCo as a spawned process, and an LLM episode mostly waits.  So each of ``--workers``
actors is a long-lived process built once (the same :class:`~capmj.bench.worker.Worker` as the
local pool) that runs up to ``--concurrency`` episodes at once in its threads
(``max_concurrency``); every episode is still its own Ray call, so results stream back one by one to
the parent's single ``episodes.jsonl`` writer and resume, crash accounting and summaries are the
local executor's.

Crashes: when an actor dies, each episode it had in flight is re-run *alone* on a fresh isolation
actor; one that kills that actor too is recorded as ``WorkerCrash`` (one retry, never lost, never
duplicated).  Stopping (Ctrl-C, SIGTERM, SIGHUP) kills the actors; a Ray started here is shut down.

The LLM disk cache is per machine unless ``CAPMJ_LLM_CACHE`` names a shared path (NFS...): the
variable is forwarded to the actors through the runtime environment (docs/scale.md).
"""

from __future__ import annotations

import os
import pickle
import threading
from collections import deque
from typing import Any, Callable, Iterable, Sequence

from capmj.bench.executor import Execution, GridStats, OnResult, RecordSink, crash_error
from capmj.bench.worker import AgentSpec, Job, Worker, ignore_sigint
from capmj.errors import ConfigError, WorkerCrash, WorkerError, describe
from capmj.llm.keys import secret_free

FORWARDED_ENV = ("CAPMJ_LLM_CACHE", "CAPMJ_PROMPTS_DIR", "MUJOCO_GL", "PYTHONHASHSEED", "LITELLM_LOCAL_MODEL_COST_MAP")
"""Environment variables of the bench process that Ray actors (possibly on other machines) get too.
No secret among them (:func:`capmj.llm.keys.is_secret_name`): actors run LLM-written code, and get
the provider's key in their ``AgentSpec``."""


def import_ray() -> Any:
    try:
        import ray
    except ImportError:
        raise ConfigError("--executor ray needs Ray: pip install 'capmj[ray]'") from None
    return ray


class EpisodeActor:
    """One worker on the cluster: builds the agent once, runs episodes in up to K threads."""

    def __init__(self, spec: AgentSpec, registered: bytes | None, llm_limit: int | None) -> None:
        ignore_sigint()
        gate = threading.BoundedSemaphore(llm_limit) if llm_limit else None
        self.worker = Worker(spec, registered, gate)

    def run(self, job: Job) -> dict[str, Any]:
        return self.worker.run_job(job)


class RayExecutor(RecordSink):
    """The :class:`~capmj.bench.executor.Executor` on Ray: ``run(jobs)`` hands each record to ``on_result``."""

    def __init__(self, agent: AgentSpec, execution: Execution, *, on_result: OnResult,
                 registered: Sequence[Any] = (), stop: Callable[[], bool] | None = None) -> None:
        super().__init__(agent, on_result)
        self.workers = max(1, execution.workers)
        self.concurrency = execution.concurrency
        self.registered = pickle.dumps(list(registered)) if registered else None
        # A cluster-wide semaphore would cost a round trip per request; each actor gets its share.
        limit = execution.max_llm_concurrency
        self.llm_limit = None if not limit else max(1, -(-limit // self.workers))
        self.address = execution.ray_address
        self.stop = stop or (lambda: False)  # checked before each new episode (run budget)

    def run(self, jobs: Iterable[Job]) -> GridStats:
        jobs = list(jobs)
        if not jobs:
            return self.stats
        ray = import_ray()
        started_here = not ray.is_initialized()
        if started_here:
            env = secret_free({k: os.environ[k] for k in FORWARDED_ENV if k in os.environ})
            kwargs: dict[str, Any] = {"runtime_env": {"env_vars": env}, "log_to_driver": False,
                                      "include_dashboard": False}
            if self.address:
                kwargs["address"] = self.address
            else:
                kwargs["num_cpus"] = self.workers + 1  # the isolation actor needs a slot too
            try:
                ray.init(**kwargs)
            except (ConnectionError, RuntimeError, ValueError) as exc:
                raise ConfigError(f"cannot connect to Ray at {self.address or 'a new local cluster'}: {exc}") from None
        cpus = float(ray.cluster_resources().get("CPU", 0))
        if cpus < self.workers:
            if started_here:
                ray.shutdown()
            raise ConfigError(f"--workers {self.workers} needs {self.workers} CPUs on the Ray cluster; "
                              f"it has {cpus:g}: lower --workers or add nodes")
        remote = ray.remote(num_cpus=1, max_restarts=0)(EpisodeActor)
        self._ray, self._remote = ray, remote
        self._actors: list[Any] = []
        try:
            self._run(deque(jobs))
        finally:
            for actor in self._actors:
                try:
                    ray.kill(actor)
                except Exception:  # noqa: BLE001 - already dead
                    pass
            if started_here:
                ray.shutdown()
        return self.stats

    def _new_actor(self, concurrency: int, cpus: float = 1.0) -> Any:
        actor = self._remote.options(max_concurrency=concurrency, num_cpus=cpus, scheduling_strategy="SPREAD").remote(
            self.agent, self.registered, self.llm_limit)
        self._actors.append(actor)
        return actor

    def _run(self, pending: deque[Job]) -> None:
        ray = self._ray
        actors = [self._new_actor(self.concurrency) for _ in range(self.workers)]
        load = [0] * len(actors)
        iso: Any = None                    # runs crash suspects one at a time
        suspects: deque[Job] = deque()
        inflight: dict[Any, tuple[int, Job]] = {}   # ObjectRef -> (actor index or -1 for iso, job)
        while pending or suspects or inflight:
            if self.stop():
                pending.clear()
                if not inflight:
                    break
            for i in range(len(actors)):
                while pending and load[i] < self.concurrency:
                    job = pending.popleft()
                    inflight[actors[i].run.remote(job)] = (i, job)
                    load[i] += 1
            if suspects and not any(i < 0 for i, _ in inflight.values()):
                # The isolation actor claims no CPU: the workers (and the replacement of the one that
                # died) hold every CPU the grid asked for, so an actor needing one would never be
                # scheduled and ray.wait would block for ever (seen on a 2-CPU cluster).  It runs one
                # suspect at a time, briefly, beside them.
                iso = iso or self._new_actor(1, cpus=0.0)
                job = suspects.popleft()
                inflight[iso.run.remote(job)] = (-1, job)
            done, _ = ray.wait(list(inflight), num_returns=1)
            ref = done[0]
            i, job = inflight.pop(ref)
            if i >= 0:
                load[i] -= 1
            try:
                rec = ray.get(ref)
            except ray.exceptions.RayActorError:
                if i < 0:   # died again while running alone
                    self.stats.crashes += 1
                    self._emit(job, self._failed(job, crash_error(" (the Ray actor died)"), WorkerCrash) | {"rrd": None})
                    iso = None
                    continue
                # the actor is gone: everything it had in flight is a suspect; replace the actor
                lost = [job]
                for r in [r for r, (k, _) in inflight.items() if k == i]:
                    lost.append(inflight.pop(r)[1])
                self.stats.retried += len(lost)
                suspects.extend(lost)
                actors[i], load[i] = self._new_actor(self.concurrency), 0
                continue
            except Exception as exc:  # noqa: BLE001 - e.g. a result that failed to deserialise
                rec = self._failed(job, f"WorkerError: {describe(exc)}", WorkerError)
            self._emit(job, rec)


__all__ = ["EpisodeActor", "FORWARDED_ENV", "RayExecutor", "import_ray"]
