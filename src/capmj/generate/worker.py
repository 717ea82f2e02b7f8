"""The worker process that executes generated task code (never the generator's own process).

``python -m capmj.generate.worker FILE --name NAME --seeds 0,1,2 --accept-rate R --tag T --events-fd N``
imports FILE, takes its ``TASK`` and runs the public task checker on it
(:func:`capmj.taskcheck.check_task`, the same code plugin authors run).  Every check's start and
result is written to the events stream (a file descriptor the parent opened) as one JSON line and
flushed at once, so when the parent kills this process for exceeding a resource limit the record
still names the check that was running.  Events go to their own descriptor, not stdout, so
whatever the task prints cannot corrupt them.

Before it loads the candidate the worker imports everything the checker uses and builds one empty
world (trusted work: the robot's mesh cache is read or computed now), then installs the runtime
guard (:mod:`capmj.confine.guard`): from then on a process, a write, a socket, native code or a
foreign import ends the process with the event recorded.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
import traceback
from pathlib import Path
from typing import IO, Any

LOAD = "load"
"""The pseudo-check of importing the module and finding ``TASK``."""


def _emit(out: IO[str], event: dict[str, Any]) -> None:
    out.write(json.dumps(event) + "\n")
    out.flush()


def _load(path: Path) -> Any:
    spec = importlib.util.spec_from_file_location(f"capmj_candidate_{path.stem}", path)
    if spec is None or spec.loader is None:
        raise ImportError(f"cannot import {path}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    if not hasattr(module, "TASK"):
        raise AttributeError("the module defines no TASK object (end it with TASK = YourTask())")
    return module.TASK


def _tb_tail(limit: int = 1500) -> str:
    text = traceback.format_exc()
    return text if len(text) <= limit else "..." + text[-limit:]


def _warm_up() -> None:
    """Trusted work done before the guard: the checker's imports and one world build."""
    import capmj.agents.oracle  # noqa: F401 - imported by the oracle checks
    import capmj.runner  # noqa: F401 - imported by the episode checks
    from capmj.sim.world import World

    World(())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m capmj.generate.worker")
    ap.add_argument("file", type=Path)
    ap.add_argument("--name", required=True)
    ap.add_argument("--seeds", required=True, help="comma-separated distinct seeds")
    ap.add_argument("--accept-rate", type=float, required=True)
    ap.add_argument("--tag", action="append", default=[])
    ap.add_argument("--events-fd", type=int, required=True, help="an open descriptor to write events to")
    ap.add_argument("--unguarded", action="store_true",
                    help="no runtime guard: only for measuring its cost (benchmarks/confinement.py)")
    args = ap.parse_args(argv)
    from capmj.confine import guard
    from capmj.taskcheck import CheckConfig, CheckResult, check_task

    with os.fdopen(args.events_fd, "a", encoding="utf-8") as out:
        _emit(out, {"start": LOAD})
        _warm_up()
        g = None if args.unguarded else guard.install(args.file.resolve(), args.events_fd)

        def start(check: str) -> None:
            if g is not None:
                g.check = check
            _emit(out, {"start": check})

        if g is not None:
            g.check = LOAD
        try:
            task = _load(args.file.resolve())
        except BaseException as e:  # noqa: BLE001 - anything the module does at import is the finding
            detail = f"{type(e).__name__}: {e}"
            _emit(out, {"result": CheckResult(LOAD, "error", detail[:500], data={"traceback": _tb_tail()}).to_dict()})
            return 0
        _emit(out, {"result": CheckResult(LOAD, "pass", "module imported, TASK found").to_dict()})
        cfg = CheckConfig(tuple(int(s) for s in args.seeds.split(",")), args.accept_rate, args.name, frozenset(args.tag),
                          allow_deprecated=False)  # a task written now uses today's protocol names
        check_task(task, cfg, on_start=start, on_result=lambda r: _emit(out, {"result": r.to_dict()}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
