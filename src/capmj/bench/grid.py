"""Run a grid of episodes (task × seed for one agent configuration) in worker processes.

Design:

* Workers are a :class:`concurrent.futures.ProcessPoolExecutor` on the ``spawn`` context (MuJoCo
  and EGL do not survive ``fork`` after GL initialisation).  Each worker builds its agent once, in
  the pool initializer, and looks tasks up in the registry (cached per process).
* Only the parent writes results: each finished episode becomes one complete line appended to
  ``episodes.jsonl`` with ``fsync`` (:class:`~capmj.bench.results.ResultsWriter`), so a killed run
  loses at most the episodes in flight, and ``--resume`` runs exactly the missing ones.
* A worker that dies (segfault, OOM kill...) breaks the pool: the pool is restarted and every
  episode that was in flight is re-run *alone*; an episode that kills its worker again while alone
  is recorded as failed with a ``WorkerCrash`` error naming the exit code, the others get their
  normal result.  So a crash costs one episode, never the run.
* Physics is deterministic and every episode is a pure function of (task, seed, agent), so the
  number of workers changes wall time only: ``--workers 2`` gives the same per-episode results as
  ``--workers 1``.  ``workers=0`` runs in the calling process (debugging; no crash isolation).
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import queue
import signal
import threading
import time
from collections import deque
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, ThreadPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

from capmj.bench.results import ResultsWriter, episode_key, sanitize
from capmj.errors import InfrastructureError, WorkerCrash, WorkerError, describe, error_facts
from capmj.records import EpisodeRecord, EpisodeResult

MP_CONTEXT = "spawn"
RECYCLE_LOGGING_WORKERS = 200
"""Episodes a worker runs before it is replaced when it writes .rrd logs (see run_jobs_to_file)."""


@dataclass(frozen=True)
class Job:
    """One episode to run: ``rrd`` is the absolute log path, or None for no log."""

    task: str
    seed: int
    rrd: str | None = None


@dataclass(frozen=True)
class AgentSpec:
    """How workers build the agent: factory name and options (``None`` options are dropped)."""

    name: str
    options: Mapping[str, Any] = field(default_factory=dict)
    images: bool = False


def rrd_relpath(task: str, seed: int, agent: str, model: str | None) -> str:
    """``rrd/<task>/<seed>-<agent>[-<model>].rrd`` relative to the run folder."""
    tail = f"{seed}-{agent}" + (f"-{_safe(model)}" if model else "")
    return f"rrd/{_safe(task)}/{tail}.rrd"


def _safe(s: str) -> str:
    return "".join(c if c.isalnum() or c in "-_.=" else "_" for c in str(s))


def failed_record(task: str, seed: int, agent: str, model: str | None, error: str, error_type: str | None,
                  **extra: Any) -> dict[str, Any]:
    """A result line for an episode that produced no result of its own (worker crash, bad task);
    ``error_type`` names the class of the failure (:mod:`capmj.errors`)."""
    rec = EpisodeResult(task, seed, agent, model, False, 0.0, 0.0, 0, 0, 0.0, 0.0, error,
                        error_type=error_type).to_dict()
    rec.update(extra)
    return rec


# ---------------------------------------------------------------------- worker side
_WORKER: dict[str, Any] = {}


def init_worker(spec: AgentSpec, registered: bytes | None = None, llm_gate: Any = None) -> None:
    """Pool initializer: build the first agent; add tasks registered by hand in the parent.

    ``llm_gate`` is a process-shared semaphore bounding the LLM requests in flight across every
    worker (``--max-llm-concurrency``); it is handed to :mod:`capmj.llm.client`.
    """
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's business
    except ValueError:  # not the main thread (in-process mode from a thread)
        pass
    _WORKER.clear()
    _WORKER["spec"] = spec
    _WORKER["idle"] = queue.SimpleQueue()
    if llm_gate is not None:
        from capmj.llm.client import set_request_gate

        set_request_gate(llm_gate)
    try:
        if registered:
            from capmj.tasks import registry

            for task in pickle.loads(registered):
                registry.register(task, replace=True)
        _WORKER["idle"].put(_build_agent(spec))
    except Exception as exc:  # noqa: BLE001 - reported per episode instead of breaking the pool
        _WORKER["init_error"] = (describe(exc), error_facts(exc)[0])


def _build_agent(spec: AgentSpec) -> Any:
    from capmj.agents.factory import make_agent

    return make_agent(spec.name, **dict(spec.options))


def _take_agent() -> Any:
    """An agent no other episode is using: agents keep per-episode state (client, transcript), so
    concurrent episodes in one worker each get their own instance, reused afterwards."""
    idle: queue.SimpleQueue = _WORKER["idle"]
    try:
        return idle.get_nowait()
    except queue.Empty:
        return _build_agent(_WORKER["spec"])


def run_job(job: Job) -> dict[str, Any]:
    """Run one episode in this worker; always returns a result record (never raises for the episode)."""
    spec: AgentSpec = _WORKER["spec"]
    if "init_error" in _WORKER:
        return failed_record(job.task, job.seed, spec.name, spec.options.get("model"), *_WORKER["init_error"])
    agent = _take_agent()
    try:
        return _run_with(agent, job, spec)
    finally:
        _WORKER["idle"].put(agent)


def _run_with(agent: Any, job: Job, spec: AgentSpec) -> dict[str, Any]:
    model = getattr(agent, "model", None)
    name = getattr(agent, "name", spec.name)
    try:
        from capmj.tasks.registry import get_task

        task = get_task(job.task)
    except Exception as exc:  # noqa: BLE001 - a broken plugin fails its own episodes only
        return failed_record(job.task, job.seed, name, model, describe(exc), error_facts(exc)[0])
    from capmj.runner import record_episode

    try:
        result = record_episode(task, job.seed, agent, job.rrd, images=spec.images)
    except Exception as exc:  # noqa: BLE001 - e.g. the log file cannot be written
        return failed_record(job.task, job.seed, name, model, describe(exc), error_facts(exc)[0])
    return sanitize(result.to_dict())


def run_batch(jobs: Sequence[Job]) -> list[dict[str, Any]]:
    """Run a batch of episodes concurrently in this worker, one thread each (``--concurrency``).

    While one episode waits on the LLM another simulates: MuJoCo releases the GIL while stepping and
    an HTTP wait holds nothing.  Each episode has its own world, agent, RNG streams and budgets; the
    sandbox traces per thread.  Records come back in the order of ``jobs``.
    """
    if len(jobs) == 1:
        return [run_job(jobs[0])]
    threads = _WORKER.get("threads")
    if threads is None or threads._max_workers < len(jobs):
        if threads is not None:
            threads.shutdown(wait=False)
        threads = _WORKER["threads"] = ThreadPoolExecutor(max_workers=len(jobs), thread_name_prefix="episode")
    return list(threads.map(run_job, jobs))


# ---------------------------------------------------------------------- parent side
@dataclass
class GridStats:
    done: int = 0
    successes: int = 0
    crashes: int = 0
    retried: int = 0
    episode_wall_s: float = 0.0   # sum of the episodes' own wall times
    wall_s: float = 0.0           # elapsed time of the whole grid


class RecordSink:
    """What every executor does with a finished episode: read the worker's result (a plain dict,
    as it crossed the process boundary), count it, hand it to ``on_result``."""

    agent: AgentSpec
    stats: GridStats
    on_result: Callable[[Job, EpisodeResult], None]

    def _emit(self, job: Job, rec: dict[str, Any]) -> None:
        result = EpisodeResult.from_dict(rec)
        self.stats.done += 1
        self.stats.successes += result.success
        self.stats.episode_wall_s += float(result.wall_s or 0.0)
        self.on_result(job, result)

    def _failed(self, job: Job, error: str, error_type: type[InfrastructureError]) -> dict[str, Any]:
        return failed_record(job.task, job.seed, self.agent.name, self.agent.options.get("model"), error,
                             error_type.__name__)


class Grid(RecordSink):
    """Runs jobs on a pool and hands every record to ``on_result`` (in the parent process).

    ``concurrency`` episodes run at once inside each worker process (see :func:`run_batch`): the
    parent submits batches of up to that many jobs.  A batch whose worker dies has every episode
    re-run alone, so crash accounting is per episode whatever the concurrency.
    """

    def __init__(self, agent: AgentSpec, *, workers: int, on_result: Callable[[Job, EpisodeResult], None],
                 registered: Sequence[Any] = (), recycle_after: int | None = None, concurrency: int = 1,
                 max_llm_concurrency: int | None = None, stop: Callable[[], bool] | None = None) -> None:
        self.agent = agent
        self.stop = stop or (lambda: False)  # checked before each new episode (run budget)
        self.workers = max(0, int(workers))
        self.concurrency = max(1, int(concurrency))
        # max_tasks_per_child counts calls, and a call is a batch
        self.recycle_after = None if recycle_after is None else max(1, recycle_after // self.concurrency)
        self.on_result = on_result
        self.registered = pickle.dumps(list(registered)) if registered else None
        self.max_llm_concurrency = max_llm_concurrency
        self.stats = GridStats()
        self._pool: ProcessPoolExecutor | None = None
        self._gate: Any = None
        self._workers: dict[int, Any] = {}  # per instance: a class-level dict would leak across grids
        self._isolating = False

    # .................................................................. pool management
    def _new_pool(self) -> ProcessPoolExecutor:
        ctx = multiprocessing.get_context(MP_CONTEXT)
        if self.max_llm_concurrency and self._gate is None:
            self._gate = ctx.BoundedSemaphore(self.max_llm_concurrency)
        return ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx, initializer=init_worker,
                                   initargs=(self.agent, self.registered, self._gate),
                                   max_tasks_per_child=self.recycle_after)

    def _track_workers(self) -> None:
        """Remember the pool's worker processes: a broken pool may forget them before we ask."""
        self._workers.update(getattr(self._pool, "_processes", None) or {})

    def _exit_codes(self) -> list[int]:
        self._track_workers()
        codes = []
        for p in list(self._workers.values()):
            try:
                p.join(timeout=1.0)  # a dying worker may need a moment; joining reaps its exit code
                code = p.exitcode
            except Exception:  # noqa: BLE001
                code = None
            if code not in (None, 0):
                codes.append(code)
        return codes

    def _kill_pool(self) -> None:
        self._workers = {}
        pool, self._pool = self._pool, None
        if pool is None:
            return
        procs = list((getattr(pool, "_processes", None) or {}).values())
        for p in procs:
            try:
                if p.is_alive():
                    p.kill()
            except Exception:  # noqa: BLE001
                pass
        pool.shutdown(wait=True, cancel_futures=True)

    # .................................................................. running
    def run(self, jobs: Iterable[Job]) -> GridStats:
        jobs = list(jobs)
        if not jobs:
            return self.stats
        if self.workers == 0:
            self._run_here(jobs)
            return self.stats
        try:
            self._run_pool(deque(jobs))
        finally:
            self._kill_pool()
        return self.stats

    def _run_here(self, jobs: list[Job]) -> None:
        """``workers=0``: run in this process (debugging, tests); the LLM gate is restored after."""
        from capmj.llm import client

        gate = threading.BoundedSemaphore(self.max_llm_concurrency) if self.max_llm_concurrency else None
        previous, sigint = client.request_gate(), signal.getsignal(signal.SIGINT)
        init_worker(self.agent, self.registered, gate)  # (it ignores SIGINT, meant for pool workers)
        signal.signal(signal.SIGINT, sigint)
        try:
            for i in range(0, len(jobs), self.concurrency):
                if self.stop():
                    break
                batch = jobs[i:i + self.concurrency]
                for job, rec in zip(batch, run_batch(batch)):
                    self._emit(job, rec)
        finally:
            client.set_request_gate(previous)
            threads = _WORKER.pop("threads", None)
            if threads is not None:
                threads.shutdown(wait=True)

    def _run_pool(self, pending: deque[Job]) -> None:
        suspects: deque[Job] = deque()   # were in flight when a worker died: re-run one at a time
        inflight: dict[Future, list[Job]] = {}
        limit = self.workers + 2
        while pending or suspects or inflight:
            if self.stop() and not inflight:
                break
            if self._pool is None:
                self._pool = self._new_pool()
            broken = False
            if not inflight:
                self._isolating = bool(suspects)
            source = suspects if self._isolating else pending
            cap, size = (1, 1) if self._isolating else (limit, self.concurrency)
            while source and len(inflight) < cap and not self.stop():
                batch = [source.popleft() for _ in range(min(size, len(source)))]
                try:
                    inflight[self._pool.submit(run_batch, batch)] = batch
                    self._track_workers()
                except BrokenProcessPool:
                    source.extendleft(reversed(batch))
                    broken = True
                    break
            if inflight and not broken:
                done, _ = wait(list(inflight), return_when=FIRST_COMPLETED)
                for fut in done:
                    batch = inflight[fut]
                    try:
                        recs = fut.result()
                    except BrokenProcessPool:
                        broken = True
                        continue
                    except Exception as exc:  # noqa: BLE001 - e.g. a result that failed to unpickle
                        recs = [self._failed(j, f"WorkerError: {describe(exc)}", WorkerError) for j in batch]
                    del inflight[fut]
                    for job, rec in zip(batch, recs):
                        self._emit(job, rec)
            if broken:
                crashed = [j for batch in inflight.values() for j in batch]
                inflight.clear()
                codes = self._exit_codes()
                self._kill_pool()
                if self._isolating and len(crashed) == 1:
                    job = crashed[0]
                    self.stats.crashes += 1
                    self._emit(job, self._failed(job, crash_error(_describe_codes(codes)), WorkerCrash) | {"rrd": None})
                else:
                    self.stats.retried += len(crashed)
                    suspects.extend(crashed)
                self._isolating = bool(suspects)


def crash_error(how: str = "") -> str:
    """The error of an episode whose worker died twice, the second time running it alone."""
    return (f"WorkerCrash: the worker process died while running this episode{how}; "
            "it was re-run alone and died again")


def _describe_codes(codes: Sequence[int]) -> str:
    if not codes:
        return ""
    parts = []
    for c in codes:
        if c < 0:
            try:
                parts.append(f"killed by {signal.Signals(-c).name}")
            except ValueError:
                parts.append(f"signal {-c}")
        else:
            parts.append(f"exit code {c}")
    return " (" + ", ".join(parts) + ")"


def run_jobs_to_file(jobs: Sequence[Job], agent: AgentSpec, *, workers: int, out_dir: Path,
                     writer: ResultsWriter, progress: Callable[[EpisodeRecord], None] | None = None,
                     registered: Sequence[Any] = (), concurrency: int = 1,
                     max_llm_concurrency: int | None = None, executor: str = "local",
                     ray_address: str | None = None, stop: Callable[[], bool] | None = None) -> GridStats:
    """Run ``jobs`` and append each record to ``writer`` (``rrd`` made relative to ``out_dir``).

    When episodes are logged, workers are replaced every :data:`RECYCLE_LOGGING_WORKERS` episodes:
    rerun never frees a Python ``RecordingStream`` (its threads outlive it, rerun issue #2116), so
    a worker writing one ``.rrd`` per episode would otherwise gain four idle threads per episode.
    """
    from capmj.bench.failures import classify
    from capmj.bench.transcripts import write_calls

    out_dir = Path(out_dir).resolve()

    def on_result(job: Job, result: EpisodeResult) -> None:
        transcript = write_calls(out_dir, result)
        rrd = result.rrd
        if rrd:
            try:
                rrd = os.path.relpath(rrd, out_dir)
            except ValueError:
                pass
        rec = EpisodeRecord.of(replace(result, rrd=rrd, calls=()), failure=classify(result), transcript=transcript)
        writer.write(rec)
        if progress is not None:
            progress(rec)

    logging = any(j.rrd for j in jobs)
    if executor == "ray":
        from capmj.bench.ray_executor import RayGrid

        grid: Grid | RayGrid = RayGrid(agent, workers=workers, on_result=on_result, registered=registered,
                                       concurrency=concurrency, max_llm_concurrency=max_llm_concurrency,
                                       address=ray_address, stop=stop)
    else:
        grid = Grid(agent, workers=workers, on_result=on_result, registered=registered,
                    recycle_after=RECYCLE_LOGGING_WORKERS if logging else None, concurrency=concurrency,
                    max_llm_concurrency=max_llm_concurrency, stop=stop)
    t0 = time.perf_counter()
    stats = grid.run(jobs)
    stats.wall_s = time.perf_counter() - t0
    return stats


__all__ = ["AgentSpec", "Grid", "GridStats", "Job", "MP_CONTEXT", "RecordSink", "crash_error", "episode_key",
           "failed_record", "init_worker", "rrd_relpath", "run_batch", "run_job", "run_jobs_to_file"]
