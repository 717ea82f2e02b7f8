"""The worker process that executes generated task code (never the generator's own process).

``python -m capmj.generate.worker FILE --name NAME --seeds 0,1,2 --accept-rate R --tag T --events OUT``
imports FILE, takes its ``TASK`` and runs the public task checker on it
(:func:`capmj.taskcheck.check_task`, the same code plugin authors run).  Every check's start and
result is appended to OUT as one JSON line and flushed at once, so when the parent kills this
process for exceeding a resource limit the record still names the check that was running.
Events go to a file, not stdout, so whatever the task prints cannot corrupt them.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
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


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m capmj.generate.worker")
    ap.add_argument("file", type=Path)
    ap.add_argument("--name", required=True)
    ap.add_argument("--seeds", required=True, help="comma-separated distinct seeds")
    ap.add_argument("--accept-rate", type=float, required=True)
    ap.add_argument("--tag", action="append", default=[])
    ap.add_argument("--events", type=Path, required=True)
    args = ap.parse_args(argv)
    from capmj.taskcheck import CheckConfig, CheckResult, check_task

    with open(args.events, "a", encoding="utf-8") as out:
        _emit(out, {"start": LOAD})
        try:
            task = _load(args.file)
        except BaseException as e:  # noqa: BLE001 - anything the module does at import is the finding
            detail = f"{type(e).__name__}: {e}"
            _emit(out, {"result": CheckResult(LOAD, "error", detail[:500], data={"traceback": _tb_tail()}).to_dict()})
            return 0
        _emit(out, {"result": CheckResult(LOAD, "pass", "module imported, TASK found").to_dict()})
        cfg = CheckConfig(tuple(int(s) for s in args.seeds.split(",")), args.accept_rate, args.name, frozenset(args.tag))
        check_task(task, cfg, on_start=lambda c: _emit(out, {"start": c}),
                   on_result=lambda r: _emit(out, {"result": r.to_dict()}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
