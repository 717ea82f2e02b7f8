"""The worker side of a grid: what runs episodes, in a pool process, a Ray actor or the caller.

A :class:`Worker` builds its agent once, looks tasks up in the registry (cached per process) and
turns every episode into a result record, never an exception: a broken plugin, an unwritable log
or an agent that cannot be built fails its own episodes only.  Every executor
(:mod:`capmj.bench.grid`, :mod:`capmj.bench.ray_executor`) runs episodes through one, so they
cannot drift apart in what an episode's record holds.
"""

from __future__ import annotations

import os
import pickle
import queue
import resource
import signal
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

from capmj.agents.factory import make_agent
from capmj.bench.results import sanitize
from capmj.bench.thumbnail import make_thumbnail
from capmj.errors import ConfigError, describe, error_facts
from capmj.llm.gate import set_request_gate
from capmj.records import EpisodeResult
from capmj.tasks import registry


@dataclass(frozen=True)
class Job:
    """One episode to run: ``rrd`` is the absolute log path, or None for no log; ``thumb`` the
    absolute path of the final top-down view written if the episode fails
    (:mod:`capmj.bench.thumbnail`), or None for none."""

    task: str
    seed: int
    rrd: str | None = None
    thumb: str | None = None


@dataclass(frozen=True)
class AgentSpec:
    """How workers build the agent: factory name and options (``None`` options are dropped).

    ``api_key`` is the LLM provider's key the parent took from its environment
    (:mod:`capmj.llm.keys`): workers get it here, in their agent's configuration, never through
    their environment; it is not one of the ``options`` (which ``config.json`` records) and no
    repr shows it."""

    name: str
    options: Mapping[str, Any] = field(default_factory=dict)
    images: bool = False
    api_key: str | None = field(default=None, repr=False)

    @property
    def model(self) -> str | None:
        """The model named in the options (the agent may resolve another; records use the agent's)."""
        return self.options.get("model")


def failed_record(task: str, seed: int, agent: str, model: str | None, error: str, error_type: str | None,
                  **extra: Any) -> dict[str, Any]:
    """A result line for an episode that produced no result of its own (worker crash, bad task);
    ``error_type`` names the class of the failure (:mod:`capmj.errors`)."""
    rec = EpisodeResult(task, seed, agent, model, False, 0.0, 0.0, 0, 0, 0.0, 0.0, error,
                        error_type=error_type).to_dict()
    rec.update(extra)
    return rec


def ignore_sigint() -> None:
    """In a worker process: Ctrl-C is the parent's business (it stops the grid and kills workers)."""
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread
        pass


class Worker:
    """Runs episodes of one agent configuration; several at once in threads (``--concurrency``).

    ``registered`` holds tasks registered by hand in the parent (pickled), which a spawned process
    would not know.  ``llm_gate`` bounds the LLM requests in flight (``--max-llm-concurrency``): a
    process-shared semaphore across pool workers, a thread one in a Ray actor or in process; it is
    handed to :mod:`capmj.llm.gate`.
    """

    def __init__(self, spec: AgentSpec, registered: bytes | None = None, llm_gate: Any = None) -> None:
        self.spec = spec
        self._idle: queue.SimpleQueue[Any] = queue.SimpleQueue()
        self._threads: ThreadPoolExecutor | None = None
        self._thread_count = 0
        self._init_error: tuple[str, str | None] | None = None
        if llm_gate is not None:
            set_request_gate(llm_gate)
        try:
            if registered:
                for task in pickle.loads(registered):
                    registry.register(task, replace=True)
            self._idle.put(self._build_agent())
        except Exception as exc:  # noqa: BLE001 - reported per episode instead of breaking the pool
            self._init_error = (describe(exc), error_facts(exc)[0])

    def _build_agent(self) -> Any:
        options = dict(self.spec.options)
        if self.spec.api_key is not None:
            options["api_key"] = self.spec.api_key
        return make_agent(self.spec.name, **options)

    def _take_agent(self) -> Any:
        """An agent no other episode is using: agents keep per-episode state (client, transcript), so
        concurrent episodes in one worker each get their own instance, reused afterwards."""
        try:
            return self._idle.get_nowait()
        except queue.Empty:
            return self._build_agent()

    def run_job(self, job: Job) -> dict[str, Any]:
        """Run one episode; always returns a result record (never raises for the episode)."""
        if self._init_error is not None:
            return failed_record(job.task, job.seed, self.spec.name, self.spec.model, *self._init_error)
        agent = self._take_agent()
        try:
            return self._run_with(agent, job)
        finally:
            self._idle.put(agent)

    def _run_with(self, agent: Any, job: Job) -> dict[str, Any]:
        model = getattr(agent, "model", None)
        name = getattr(agent, "name", self.spec.name)
        try:
            task = registry.get_task(job.task)
        except Exception as exc:  # noqa: BLE001 - a broken plugin fails its own episodes only
            return failed_record(job.task, job.seed, name, model, describe(exc), error_facts(exc)[0])
        from capmj.runner import record_episode, run_episode  # MuJoCo: loaded by the workers, not the parent

        try:
            if job.rrd is None:  # --no-log
                result = run_episode(task, job.seed, agent)
            else:
                result = record_episode(task, job.seed, agent, job.rrd, images=self.spec.images)
        except Exception as exc:  # noqa: BLE001 - e.g. the log file cannot be written
            return failed_record(job.task, job.seed, name, model, describe(exc), error_facts(exc)[0])
        record = sanitize(result.to_dict())
        make_thumbnail(job.thumb, task, record)  # failed episodes only; never raises
        return record

    def run_batch(self, jobs: Sequence[Job]) -> list[dict[str, Any]]:
        """Run a batch of episodes concurrently, one thread each (``--concurrency``).

        While one episode waits on the LLM another simulates: MuJoCo releases the GIL while stepping and
        an HTTP wait holds nothing.  Each episode has its own world, agent, RNG streams and budgets; the
        sandbox traces per thread.  Records come back in the order of ``jobs``.
        """
        if len(jobs) == 1:
            return [self.run_job(jobs[0])]
        if self._threads is None or self._thread_count < len(jobs):
            if self._threads is not None:
                self._threads.shutdown(wait=False)
            self._threads = ThreadPoolExecutor(max_workers=len(jobs), thread_name_prefix="episode")
            self._thread_count = len(jobs)
        return list(self._threads.map(self.run_job, jobs))

    def close(self) -> None:
        """Wait for the episode threads (in-process runs: nothing may outlive the grid)."""
        if self._threads is not None:
            self._threads.shutdown(wait=True)
            self._threads = None


# ---------------------------------------------------------------------- in a pool process
_pool_worker: Worker | None = None
"""The :class:`Worker` of this pool process.  A ``ProcessPoolExecutor`` initializer can hand state
to the calls that follow only through the process itself, so this one slot is set by
:func:`init_pool_worker` in spawned pool processes, and by nothing else (the in-process executor
and Ray actors hold their own ``Worker``)."""


MEMORY_ENV = "CAPMJ_WORKER_MEMORY_MB"
"""Environment variable: the data-segment limit (``RLIMIT_DATA``, MiB) of each pool worker;
``0`` turns it off.  Default :data:`DEFAULT_MEMORY_MB`."""
DEFAULT_MEMORY_MB = 8192


def limit_memory() -> int | None:
    """Cap this process's private memory (``RLIMIT_DATA``): the backstop behind the sandbox's size
    budgets, so an allocation they cannot foresee ends as a ``MemoryError`` of one episode (a
    recorded ``budget`` failure) instead of the machine's memory.  Returns the limit in MiB."""
    try:
        mb = int(os.environ.get(MEMORY_ENV, DEFAULT_MEMORY_MB))
    except ValueError:
        raise ConfigError(f"{MEMORY_ENV} must be a whole number of MiB (0: no limit), "
                          f"not {os.environ.get(MEMORY_ENV)!r}") from None
    if mb <= 0:
        return None
    soft, hard = resource.getrlimit(resource.RLIMIT_DATA)
    limit = mb << 20 if hard == resource.RLIM_INFINITY else min(mb << 20, hard)
    resource.setrlimit(resource.RLIMIT_DATA, (limit, hard))
    return mb


def init_pool_worker(spec: AgentSpec, registered: bytes | None = None, llm_gate: Any = None) -> None:
    """Pool initializer: this process's :class:`Worker`, under the memory limit."""
    global _pool_worker
    ignore_sigint()
    limit_memory()
    _pool_worker = Worker(spec, registered, llm_gate)


def run_pool_batch(jobs: Sequence[Job]) -> list[dict[str, Any]]:
    """What the pool's parent submits: a batch for this process's worker."""
    if _pool_worker is None:
        raise RuntimeError("run_pool_batch runs in a pool process started with init_pool_worker")
    return _pool_worker.run_batch(jobs)


__all__ = ["AgentSpec", "DEFAULT_MEMORY_MB", "Job", "MEMORY_ENV", "Worker", "failed_record", "ignore_sigint",
           "init_pool_worker", "limit_memory", "run_pool_batch"]
