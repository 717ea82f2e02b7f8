"""Run the checks of a generated task in a separate, confined process under resource limits.

Generated code is untrusted: it runs only in :mod:`capmj.generate.worker`, started here with
``RLIMIT_CPU`` (a ``while True`` gets SIGXCPU), ``RLIMIT_AS`` (a runaway allocation gets a
``MemoryError``) and a wall-clock timeout (a process sleeping or blocked is killed with its whole
process group), inside the OS layer where the machine allows it (:mod:`capmj.confine.oslayer`:
no network, read-only file system) and under the worker's runtime guard
(:mod:`capmj.confine.guard`).  The worker streams each check's start and result to an events
descriptor; a check that was running when the process died is recorded as an ``error`` naming
the limit or the refused event, and the checks after it as skipped, so every outcome is explained.
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

from capmj.confine.guard import VIOLATION_EXIT
from capmj.confine.oslayer import confine_child
from capmj.generate.config import Limits
from capmj.generate.worker import LOAD
from capmj.taskcheck import CHECKS, CheckResult

ORDER = (LOAD, *CHECKS)
_THREADS_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


@dataclass(frozen=True)
class IsolatedRun:
    """The worker's results in :data:`ORDER`, how it ended, and its wall time.

    ``violation`` is the event the runtime guard refused (the candidate is hostile or careless:
    rejected without a repair round), ``os_layer`` what the OS layer achieved in this process.
    """

    results: tuple[CheckResult, ...]
    ended: str
    wall_s: float
    violation: dict[str, str] | None = None
    os_layer: dict[str, object] | None = None


def _limit(limits: Limits, events_fd: int, os_layer: bool):
    confine = confine_child(events_fd) if os_layer else None

    def apply() -> None:  # runs in the child between fork and exec
        resource.setrlimit(resource.RLIMIT_CPU, (limits.cpu_s, limits.cpu_s + 2))
        mem = limits.memory_mb * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (mem, mem))
        if confine is not None:
            confine()
    return apply


def _why(returncode: int | None, timed_out: bool, limits: Limits, violation: dict[str, str] | None) -> str:
    if violation is not None:
        return f"refused by the runtime guard: {violation['detail']}"
    if timed_out:
        return f"killed: wall-clock limit of {limits.wall_s:g} s exceeded"
    if returncode is not None and returncode < 0:
        sig = -returncode
        if sig in (signal.SIGXCPU, signal.SIGKILL):
            return f"killed: CPU-time limit of {limits.cpu_s} s exceeded ({signal.Signals(sig).name})"
        return f"killed by signal {signal.Signals(sig).name}"
    return f"worker exited with code {returncode}"


def run_isolated(path: Path, *, name: str, seeds: tuple[int, ...], accept_rate: float, tags: tuple[str, ...],
                 limits: Limits, os_layer: bool = True, guarded: bool = True) -> IsolatedRun:
    """Check the task module at ``path`` in a limited, confined worker process.

    ``os_layer=False`` and ``guarded=False`` switch a layer off; only the tests and
    ``benchmarks/confinement.py`` do, to show what each layer stops on its own and what it costs.
    """
    with tempfile.TemporaryDirectory(prefix="capmj-gen-") as tmp:
        events = Path(tmp) / "events.jsonl"
        fd = os.open(events, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
        cmd = [sys.executable, "-m", "capmj.generate.worker", str(Path(path).resolve()), "--name", name,
               "--seeds", ",".join(map(str, seeds)), "--accept-rate", repr(accept_rate), "--events-fd", str(fd)]
        for t in tags:
            cmd += ["--tag", t]
        if not guarded:
            cmd.append("--unguarded")
        env = {**os.environ, **_THREADS_ENV}
        t0 = time.perf_counter()
        try:
            proc = subprocess.Popen(cmd, cwd=tmp, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                    stderr=subprocess.PIPE, preexec_fn=_limit(limits, fd, os_layer),
                                    start_new_session=True, pass_fds=(fd,))
        finally:
            os.close(fd)
        timed_out = False
        try:
            _, err = proc.communicate(timeout=limits.wall_s)
        except subprocess.TimeoutExpired:
            timed_out = True
            os.killpg(proc.pid, signal.SIGKILL)
            _, err = proc.communicate()
        wall = time.perf_counter() - t0
        lines = events.read_text(encoding="utf-8").splitlines() if events.exists() else []
    return _collect(lines, proc.returncode, timed_out, err, limits, wall)


def _collect(lines: list[str], returncode: int | None, timed_out: bool, err: bytes | None, limits: Limits,
             wall: float) -> IsolatedRun:
    """The worker's events as results in :data:`ORDER`, every gap explained."""
    results: list[CheckResult] = []
    running: str | None = None
    violation: dict[str, str] | None = None
    os_report: dict[str, object] | None = None
    for line in lines:
        try:
            ev = json.loads(line)
        except json.JSONDecodeError:
            continue  # a line cut by a kill
        if "start" in ev:
            running = ev["start"]
        elif "violation" in ev:
            violation = ev["violation"]
        elif "os_layer" in ev:
            os_report = ev["os_layer"]
        elif "result" in ev:
            results.append(CheckResult.from_dict(ev["result"]))
            running = None
    if violation is None and returncode == VIOLATION_EXIT:
        violation = {"event": "?", "detail": "an event (not recorded: the events stream was gone)", "check": running or ""}
    if violation is not None:  # whatever the results say, a refused event fails the candidate
        results = [r for r in results if r.name != violation.get("check")]
    done = {r.name for r in results}
    ended = "completed"
    if violation is not None or returncode != 0 or timed_out or len(results) < len(ORDER) and not any(
            r.outcome in ("fail", "error") for r in results):
        ended = _why(returncode, timed_out, limits, violation)
        tail = (err or b"").decode(errors="replace").strip().splitlines()[-3:]
        first = (violation or {}).get("check") or running or next((c for c in ORDER if c not in done), LOAD)
        if first not in done:
            stderr = f"; stderr: {' | '.join(tail)}" if tail and violation is None else ""
            results.append(CheckResult(first, "error", (f"{ended} during {first}" + stderr)[:600]))
    done = {r.name for r in results}
    for c in ORDER:
        if c not in done:
            results.append(CheckResult(c, "skip", "not run"))
    return IsolatedRun(tuple(sorted(results, key=lambda r: ORDER.index(r.name))), ended, wall, violation, os_report)


__all__ = ["IsolatedRun", "ORDER", "run_isolated"]
