"""Run a grid of episodes (task × seed for one agent configuration) in local worker processes.

Design:

* Workers are a :class:`~capmj.bench.pool.SpawnPool` (``spawn``: MuJoCo and EGL do not survive
  ``fork`` after GL initialisation).  Each pool process builds its :class:`~capmj.bench.worker.Worker`
  once, in the pool initializer, and looks tasks up in the registry (cached per process).
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

:func:`run_jobs_to_file` picks the executor (this one or :mod:`capmj.bench.ray_executor`) and
writes what it hands back into the run folder.
"""

from __future__ import annotations

import multiprocessing
import pickle
import threading
import time
from collections import deque
from concurrent.futures import FIRST_COMPLETED, Future, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import replace
from typing import Any, Callable, Iterable, Sequence

from capmj.bench.executor import (
    Execution,
    Executor,
    GridStats,
    OnResult,
    RecordSink,
    crash_error,
    describe_exit_codes,
)
from capmj.bench.failures import classify
from capmj.bench.pool import START_METHOD, SpawnPool
from capmj.bench.results import ResultsWriter
from capmj.bench.rundir import RunDir
from capmj.bench.transcripts import write_calls
from capmj.bench.worker import AgentSpec, Job, Worker, init_pool_worker, run_pool_batch
from capmj.errors import WorkerCrash, WorkerError, describe
from capmj.llm.gate import request_gate, set_request_gate
from capmj.records import EpisodeRecord, EpisodeResult

RECYCLE_LOGGING_WORKERS = 200
"""Episodes a worker runs before it is replaced when it writes .rrd logs (see run_jobs_to_file)."""


class LocalExecutor(RecordSink):
    """Runs jobs on a pool of local processes and hands every record to ``on_result`` (in the parent).

    ``concurrency`` episodes run at once inside each worker process (see
    :meth:`~capmj.bench.worker.Worker.run_batch`): the parent submits batches of up to that many
    jobs.  A batch whose worker dies has every episode re-run alone, so crash accounting is per
    episode whatever the concurrency.
    """

    def __init__(self, agent: AgentSpec, execution: Execution, *, on_result: OnResult,
                 registered: Sequence[Any] = (), recycle_after: int | None = None,
                 stop: Callable[[], bool] | None = None) -> None:
        super().__init__(agent, on_result)
        self.stop = stop or (lambda: False)  # checked before each new episode (run budget)
        self.workers = execution.workers
        self.concurrency = execution.concurrency
        # max_tasks_per_child counts calls, and a call is a batch
        self.recycle_after = None if recycle_after is None else max(1, recycle_after // self.concurrency)
        self.registered = pickle.dumps(list(registered)) if registered else None
        self.max_llm_concurrency = execution.max_llm_concurrency
        self._pool: SpawnPool | None = None
        self._gate: Any = None
        self._isolating = False

    # .................................................................. pool management
    def _new_pool(self) -> SpawnPool:
        if self.max_llm_concurrency and self._gate is None:
            self._gate = multiprocessing.get_context(START_METHOD).BoundedSemaphore(self.max_llm_concurrency)
        return SpawnPool(self.workers, initializer=init_pool_worker, initargs=(self.agent, self.registered, self._gate),
                         max_tasks_per_child=self.recycle_after)

    def _kill_pool(self) -> None:
        pool, self._pool = self._pool, None
        if pool is not None:
            pool.kill()

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
        gate = threading.BoundedSemaphore(self.max_llm_concurrency) if self.max_llm_concurrency else None
        previous = request_gate()
        worker = Worker(self.agent, self.registered, gate)
        try:
            for i in range(0, len(jobs), self.concurrency):
                if self.stop():
                    break
                batch = jobs[i:i + self.concurrency]
                for job, rec in zip(batch, worker.run_batch(batch)):
                    self._emit(job, rec)
        finally:
            set_request_gate(previous)
            worker.close()

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
                    inflight[self._pool.submit(run_pool_batch, batch)] = batch
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
                codes = self._pool.exit_codes() if self._pool is not None else []
                self._kill_pool()
                if self._isolating and len(crashed) == 1:
                    job = crashed[0]
                    self.stats.crashes += 1
                    self._emit(job, self._failed(job, crash_error(describe_exit_codes(codes)), WorkerCrash) | {"rrd": None})
                else:
                    self.stats.retried += len(crashed)
                    suspects.extend(crashed)
                self._isolating = bool(suspects)


def make_executor(agent: AgentSpec, execution: Execution, *, on_result: OnResult, registered: Sequence[Any] = (),
                  logging: bool = False, stop: Callable[[], bool] | None = None) -> Executor:
    """The executor ``execution`` names.  When episodes are logged, local workers are replaced every
    :data:`RECYCLE_LOGGING_WORKERS` episodes: rerun never frees a Python ``RecordingStream`` (its
    threads outlive it, rerun issue #2116), so a worker writing one ``.rrd`` per episode would
    otherwise gain four idle threads per episode."""
    if execution.executor == "ray":
        from capmj.bench.ray_executor import RayExecutor

        return RayExecutor(agent, execution, on_result=on_result, registered=registered, stop=stop)
    return LocalExecutor(agent, execution, on_result=on_result, registered=registered,
                         recycle_after=RECYCLE_LOGGING_WORKERS if logging else None, stop=stop)


def run_jobs_to_file(jobs: Sequence[Job], agent: AgentSpec, execution: Execution, *, run_dir: RunDir,
                     writer: ResultsWriter, progress: Callable[[EpisodeRecord], None] | None = None,
                     registered: Sequence[Any] = (), stop: Callable[[], bool] | None = None,
                     config: str | None = None) -> GridStats:
    """Run ``jobs`` and append each record to ``writer``: LLM calls moved to the episode's transcript
    file, ``rrd`` made relative to the run folder, the failure classified, and the record named
    after its configuration (``config``, of a ``--configs`` grid; None: the run's only one)."""
    run_dir = run_dir.resolved()

    def on_result(job: Job, result: EpisodeResult) -> None:
        transcript = write_calls(run_dir.root, result, config)
        rrd = run_dir.relative(result.rrd) if result.rrd else result.rrd
        rec = EpisodeRecord.of(replace(result, rrd=rrd, calls=()), failure=classify(result), transcript=transcript,
                               config=config)
        writer.write(rec)
        if progress is not None:
            progress(rec)

    grid = make_executor(agent, execution, on_result=on_result, registered=registered,
                         logging=any(j.rrd for j in jobs), stop=stop)
    t0 = time.perf_counter()
    stats = grid.run(jobs)
    stats.wall_s = time.perf_counter() - t0
    return stats


__all__ = ["LocalExecutor", "RECYCLE_LOGGING_WORKERS", "make_executor", "run_jobs_to_file"]
