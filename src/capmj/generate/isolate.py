"""Run the checks of a generated task in a separate process under resource limits.

Generated code is untrusted: it runs only in :mod:`capmj.generate.worker`, started here with
``RLIMIT_CPU`` (a ``while True`` gets SIGXCPU), ``RLIMIT_AS`` (a runaway allocation gets a
``MemoryError``) and a wall-clock timeout (a process sleeping or blocked is killed with its whole
process group).  The worker streams each check's start and result to an events file; a check
that was running when the process died is recorded as an ``error`` naming the limit, and the
checks after it as skipped, so every outcome is explained.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from capmj.generate.config import Limits
from capmj.generate.worker import LOAD
from capmj.taskcheck import CHECKS, CheckResult

ORDER = (LOAD, *CHECKS)
_THREADS_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


@dataclass(frozen=True)
class IsolatedRun:
    """The worker's results in :data:`ORDER`, how it ended, and its wall time."""

    results: tuple[CheckResult, ...]
    ended: str
    wall_s: float


def _limit(limits: Limits):
    def apply() -> None:  # runs in the child between fork and exec
        resource.setrlimit(resource.RLIMIT_CPU, (limits.cpu_s, limits.cpu_s + 2))
        mem = limits.memory_mb * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (mem, mem))
    return apply


def _why(returncode: int | None, timed_out: bool, limits: Limits) -> str:
    if timed_out:
        return f"killed: wall-clock limit of {limits.wall_s:g} s exceeded"
    if returncode is not None and returncode < 0:
        sig = -returncode
        if sig in (signal.SIGXCPU, signal.SIGKILL):
            return f"killed: CPU-time limit of {limits.cpu_s} s exceeded ({signal.Signals(sig).name})"
        return f"killed by signal {signal.Signals(sig).name}"
    return f"worker exited with code {returncode}"


def run_isolated(path: Path, *, name: str, seeds: tuple[int, ...], accept_rate: float, tags: tuple[str, ...],
                 limits: Limits) -> IsolatedRun:
    """Check the task module at ``path`` in a limited worker process."""
    with tempfile.TemporaryDirectory(prefix="capmj-gen-") as tmp:
        events = Path(tmp) / "events.jsonl"
        cmd = [sys.executable, "-m", "capmj.generate.worker", str(path), "--name", name,
               "--seeds", ",".join(map(str, seeds)), "--accept-rate", repr(accept_rate), "--events", str(events)]
        for t in tags:
            cmd += ["--tag", t]
        env = {**os.environ, **_THREADS_ENV}
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, cwd=tmp, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, preexec_fn=_limit(limits), start_new_session=True)
        timed_out = False
        try:
            _, err = proc.communicate(timeout=limits.wall_s)
        except subprocess.TimeoutExpired:
            timed_out = True
            os.killpg(proc.pid, signal.SIGKILL)
            _, err = proc.communicate()
        wall = time.perf_counter() - t0
        lines = events.read_text(encoding="utf-8").splitlines() if events.exists() else []
    results: list[CheckResult] = []
    running: str | None = None
    for line in lines:
        ev = json.loads(line)
        if "start" in ev:
            running = ev["start"]
        else:
            results.append(CheckResult.from_dict(ev["result"]))
            running = None
    ended = "completed"
    done = {r.name for r in results}
    if proc.returncode != 0 or timed_out or len(results) < len(ORDER) and not any(
            r.outcome in ("fail", "error") for r in results):
        ended = _why(proc.returncode, timed_out, limits)
        tail = (err or b"").decode(errors="replace").strip().splitlines()[-3:]
        first = running or next((c for c in ORDER if c not in done), LOAD)
        if first not in done:
            detail = ended + (f" during {first}" if first else "") + (f"; stderr: {' | '.join(tail)}" if tail else "")
            results.append(CheckResult(first, "error", detail[:600]))
    done = {r.name for r in results}
    for c in ORDER:
        if c not in done:
            results.append(CheckResult(c, "skip", "not run"))
    return IsolatedRun(tuple(sorted(results, key=lambda r: ORDER.index(r.name))), ended, wall)


__all__ = ["IsolatedRun", "ORDER", "run_isolated"]
