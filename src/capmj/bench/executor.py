"""What every grid executor promises (local processes, Ray), and what they share.

An executor takes the jobs of a grid and hands every finished episode, in the parent process, to
one callback; it never writes files itself (only the parent's writer appends to
``episodes.jsonl``).  :class:`Execution` is how many workers and episodes in flight, on which
executor: the part of a run's configuration that changes wall time only, never an episode's
result (physics is deterministic and every episode is a pure function of task, seed and agent).
"""

from __future__ import annotations

import signal
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Protocol, Sequence

from capmj.bench.options import EXECUTORS
from capmj.bench.worker import AgentSpec, Job, failed_record
from capmj.errors import ConfigError, InfrastructureError
from capmj.records import EpisodeResult

OnResult = Callable[[Job, EpisodeResult], None]
"""What an executor calls with every finished episode, in the parent process."""


@dataclass(frozen=True)
class Execution:
    """How a grid runs: ``workers`` processes (0 = in the calling process) or Ray actors, each with
    up to ``concurrency`` episodes in flight, at most ``max_llm_concurrency`` LLM requests in flight
    across all of them (None: no cap)."""

    workers: int
    concurrency: int = 1
    max_llm_concurrency: int | None = None
    executor: str = "local"
    ray_address: str | None = None

    def __post_init__(self) -> None:
        if self.workers < 0:
            raise ConfigError(f"--workers must be >= 0, got {self.workers}")
        if self.concurrency < 1:
            raise ConfigError(f"--concurrency must be >= 1, got {self.concurrency}")
        if self.max_llm_concurrency is not None and self.max_llm_concurrency < 1:
            raise ConfigError(f"--max-llm-concurrency must be >= 1, got {self.max_llm_concurrency}")
        if self.executor not in EXECUTORS:
            raise ConfigError(f"unknown executor {self.executor!r}; valid: {', '.join(EXECUTORS)}")
        if self.executor == "ray" and self.workers < 1:
            raise ConfigError("--executor ray needs --workers >= 1 (Ray actors)")


@dataclass
class GridStats:
    done: int = 0
    successes: int = 0
    crashes: int = 0
    retried: int = 0
    episode_wall_s: float = 0.0   # sum of the episodes' own wall times
    wall_s: float = 0.0           # elapsed time of the whole grid


class Executor(Protocol):
    """Runs jobs and hands every record to its ``on_result``; returns the grid's counts."""

    stats: GridStats

    def run(self, jobs: Iterable[Job]) -> GridStats: ...


class RecordSink:
    """What every executor does with a finished episode: read the worker's result (a plain dict,
    as it crossed the process boundary), count it, hand it to ``on_result``."""

    def __init__(self, agent: AgentSpec, on_result: OnResult) -> None:
        self.agent = agent
        self.on_result = on_result
        self.stats = GridStats()

    def _emit(self, job: Job, rec: dict[str, Any]) -> None:
        result = EpisodeResult.from_dict(rec)
        self.stats.done += 1
        self.stats.successes += result.success
        self.stats.episode_wall_s += float(result.wall_s or 0.0)
        self.on_result(job, result)

    def _failed(self, job: Job, error: str, error_type: type[InfrastructureError]) -> dict[str, Any]:
        return failed_record(job.task, job.seed, self.agent.name, self.agent.model, error, error_type.__name__)


def crash_error(how: str = "") -> str:
    """The error of an episode whose worker died twice, the second time running it alone."""
    return (f"WorkerCrash: the worker process died while running this episode{how}; "
            "it was re-run alone and died again")


def describe_exit_codes(codes: Sequence[int]) -> str:
    """`` (killed by SIGKILL, exit code 3)`` for the exit codes of dead workers ('' for none)."""
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


__all__ = ["Execution", "Executor", "GridStats", "OnResult", "RecordSink", "crash_error",
           "describe_exit_codes"]
