"""One agent in state and in rgbd mode, task by task: success, failure labels and perception error.

Reads two finished ``python -m capmj.bench`` run folders of the same agent over the same tasks
and seeds, one per perception mode, and prints one JSON object: per task the successes and the
failure labels in each mode and the rgbd run's pooled perception error (``summary.json``'s
``perception`` block: reset and after-move views, misses, false detections, label errors, median
and max position error), then every episode that failed in either mode, side by side.  Nothing
is re-run: the figures are the run folders' own, so the JSON can be rebuilt from them at any time.

    python -m capmj.bench --agent reference --perception rgbd  --tasks all --seeds 10001:10021:2 --out runs/rgbd
    python -m capmj.bench --agent reference --perception state --tasks all --seeds 10001:10021:2 --out runs/state
    python benchmarks/perception_grid.py --state runs/state --rgbd runs/rgbd > grid.json
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path
from typing import Any

from capmj.bench.results import load_json, read_records


def _run(folder: Path) -> tuple[dict[tuple[str, int], Any], dict[str, Any], dict[str, Any]]:
    records, bad = read_records(folder / "episodes.jsonl")
    if bad:
        raise SystemExit(f"{folder}: {bad} unreadable line(s) in episodes.jsonl")
    summary = load_json(folder / "summary.json") or {}
    config = load_json(folder / "config.json") or {}
    return {(r.task, r.seed): r for r in records}, summary, config


def _labels(recs: list[Any]) -> dict[str, int]:
    return dict(sorted(Counter(r.failure for r in recs if not r.success).items()))


def _why(r: Any) -> str | None:
    if r.success:
        return None
    return r.error or "; ".join(r.diagnostics[:2]) or None


def _revisions(config: dict[str, Any]) -> list[Any]:
    """The git state of the code of each part of a run: its start, then every ``--resume``."""
    parts = [config.get("manifest", {}), *(r.get("manifest", {}) for r in config.get("resumes", []))]
    return [m.get("git") for m in parts]


def compare(state_dir: Path, rgbd_dir: Path) -> dict[str, Any]:
    state, _, state_cfg = _run(state_dir)
    rgbd, rgbd_summary, rgbd_cfg = _run(rgbd_dir)
    only = sorted(set(state) ^ set(rgbd))  # e.g. one run stopped early: compare the episodes both ran
    state = {k: v for k, v in state.items() if k in rgbd}
    rgbd = {k: v for k, v in rgbd.items() if k in state}
    tasks: dict[str, Any] = {}
    for task in sorted({t for t, _ in state}):
        s = [state[k] for k in sorted(state) if k[0] == task]
        g = [rgbd[k] for k in sorted(rgbd) if k[0] == task]
        per_config = (rgbd_summary.get("tasks", {}).get(task) or {})
        pooled = next(iter(per_config.values()), {}).get("perception")
        tasks[task] = {"episodes": len(s),
                       "state": {"successes": sum(r.success for r in s), "failures": _labels(s)},
                       "rgbd": {"successes": sum(r.success for r in g), "failures": _labels(g)},
                       "perception": pooled}
    failed = [{"task": t, "seed": seed,
               "state": {"success": state[(t, seed)].success, "failure": state[(t, seed)].failure,
                         "why": _why(state[(t, seed)])},
               "rgbd": {"success": rgbd[(t, seed)].success, "failure": rgbd[(t, seed)].failure,
                        "why": _why(rgbd[(t, seed)]),
                        "perception_erred": bool(rgbd[(t, seed)].perception
                                                 and rgbd[(t, seed)].perception.erred(rgbd[(t, seed)].attempts))}}
              for t, seed in sorted(state) if not (state[(t, seed)].success and rgbd[(t, seed)].success)]
    n = len(state)
    seeds = sorted({seed for _, seed in state})
    return {"agent": sorted({r.agent for r in state.values()}), "tasks_n": len(tasks), "seeds": seeds,
            "left_out": [list(k) for k in only],
            "episodes_per_mode": n,
            "success": {"state": sum(r.success for r in state.values()) / n,
                        "rgbd": sum(r.success for r in rgbd.values()) / n},
            "failures": {"state": _labels(list(state.values())), "rgbd": _labels(list(rgbd.values()))},
            "perception": next(iter(rgbd_summary.get("overall", {}).values()), {}).get("perception"),
            "code": {"state": _revisions(state_cfg), "rgbd": _revisions(rgbd_cfg)},
            "tasks": tasks, "failed_episodes": failed}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--state", type=Path, required=True, help="run folder of the agent in state mode")
    ap.add_argument("--rgbd", type=Path, required=True, help="run folder of the same grid in rgbd mode")
    ap.add_argument("--note", default=None, help="how the runs were made (machine, commands), kept in the JSON")
    args = ap.parse_args(argv)
    out = compare(args.state, args.rgbd)
    if args.note:
        out["note"] = args.note
    json.dump(out, sys.stdout, indent=1, sort_keys=True)
    print()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
