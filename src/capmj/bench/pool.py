"""The one way capmj's benchmarks start worker processes: a ``spawn`` pool that knows its processes.

Why ``spawn``: MuJoCo and EGL do not survive ``fork`` after GL initialisation, and a forked worker
inherits whatever threads and locks the parent held (litellm's, rerun's).  Every pool of the bench
and of the scripts in ``benchmarks/`` is made here, so none forks by the platform's default.

Why it tracks its processes: when a worker dies (segfault, OOM kill), the grid names the exit code
in the episode's error, and a broken ``ProcessPoolExecutor`` forgets its processes.  The pool's
context is the spawn context whose ``Process`` also keeps every process it starts (the executor
starts its workers through its context), so no private attribute of the executor is read.
"""

from __future__ import annotations

import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import resource_tracker
from multiprocessing.context import SpawnContext, SpawnProcess
from typing import Any, Callable

START_METHOD = "spawn"


class TrackingSpawnContext(SpawnContext):
    """A spawn context that remembers every process started through it."""

    def __init__(self) -> None:
        self.started: list[SpawnProcess] = []

    def Process(self, *args: Any, **kwargs: Any) -> SpawnProcess:  # type: ignore[override]  # noqa: N802 - the context API's name
        process = SpawnProcess(*args, **kwargs)
        self.started.append(process)
        return process


def _exit_code(process: SpawnProcess, timeout_s: float) -> int | None:
    """``process``'s exit code, waiting up to ``timeout_s`` for it (None: still running or never started).

    Why the retry: a broken executor's manager thread reaps its dead workers itself.  When it wins
    the ``waitpid`` race, ``join`` here returns on the closed sentinel but reads no code (the reaping
    thread has not stored it yet), and the grid would lose the cause of the death.
    """
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            process.join(timeout=max(0.0, deadline - time.monotonic()))
            code = process.exitcode
        except Exception:  # noqa: BLE001 - a process that never started
            return None
        if code is not None or time.monotonic() >= deadline:
            return code
        time.sleep(0.01)


class SpawnPool(ProcessPoolExecutor):
    """A ``ProcessPoolExecutor`` on a :class:`TrackingSpawnContext`; :meth:`kill` ends it at once."""

    def __init__(self, workers: int, *, initializer: Callable[..., object] | None = None, initargs: tuple[Any, ...] = (),
                 max_tasks_per_child: int | None = None, context: TrackingSpawnContext | None = None) -> None:
        self.context = context or TrackingSpawnContext()
        super().__init__(max_workers=workers, mp_context=self.context, initializer=initializer, initargs=initargs,
                         max_tasks_per_child=max_tasks_per_child)

    def processes(self) -> list[SpawnProcess]:
        """Every worker process this pool started (running, recycled or dead)."""
        return list(self.context.started)

    def exit_codes(self, timeout_s: float = 1.0) -> list[int]:
        """The non-zero exit codes of the pool's processes; a dying one gets ``timeout_s`` to be reaped."""
        codes = []
        for p in self.processes():
            code = _exit_code(p, timeout_s)
            if code not in (None, 0):
                codes.append(code)
        return codes

    def kill(self) -> None:
        """Kill the workers (episodes in flight are lost; the caller re-runs them) and shut down."""
        for p in self.processes():
            try:
                if p.is_alive():
                    p.kill()
            except Exception:  # noqa: BLE001 - never started or already reaped
                pass
        self.shutdown(wait=True, cancel_futures=True)


def stop_resource_tracker() -> None:
    """End multiprocessing's resource-tracker process now rather than when this process exits.

    Call it once a stopped grid's workers are dead: the tracker (started by the first spawn) would
    otherwise outlive them while the summary is written, and with it a stopped run's process tree
    (CI cancels and ``timeout`` wait for it).  CPython has no public way to end the tracker (the
    tracker ignores SIGINT and SIGTERM, and only the parent's private handle on its pipe ends it
    cleanly, unlinking what it tracks), so this is the one private attribute the bench reads; it
    is looked up defensively and does nothing where it is missing.
    """
    stop = getattr(getattr(resource_tracker, "_resource_tracker", None), "_stop", None)
    if stop is None:
        return
    try:
        stop()
    except Exception:  # noqa: BLE001 - best effort; the tracker ends with us anyway
        pass


def spawn_pool(workers: int, *, initializer: Callable[..., object] | None = None, initargs: tuple[Any, ...] = (),
               max_tasks_per_child: int | None = None) -> SpawnPool:
    """A pool of ``workers`` spawned processes (see the module docstring)."""
    return SpawnPool(workers, initializer=initializer, initargs=initargs, max_tasks_per_child=max_tasks_per_child)


__all__ = ["START_METHOD", "SpawnPool", "TrackingSpawnContext", "spawn_pool", "stop_resource_tracker"]
