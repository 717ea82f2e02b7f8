"""Shared runner of ``oracle.py`` and ``reference.py``: one agent over tasks × test seeds.

Episodes are spread over ``--workers`` spawned processes (:func:`capmj.bench.pool.spawn_pool`), one
(task, seed) at a time, so the load stays balanced and each finished episode is printed at once:
one JSON line per episode on stderr
(task, seed, success, primitives, wall seconds, error, diagnostics), then one per task, and last
a summary JSON object on stdout: success rate, mean primitives and wall seconds per task, and
every failure with its seed, goal, error and diagnostics.  Results do not depend on the number of
workers.  Tasks default to every registered task (A–J, the generated tasks and any installed
plugin task); ``--tasks`` takes names, tags or ``all``.
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import as_completed

from capmj.bench.pool import spawn_pool
from capmj.tasks.registry import get_task, resolve


def run_one(kind: str, name: str, seed: int) -> dict:
    """One episode of agent ``kind`` ("oracle" or "reference") as a JSON-friendly dict."""
    from capmj.runner import run_episode

    if kind == "oracle":
        from capmj.agents.oracle import OracleAgent as Agent
    else:
        from capmj.agents.reference import ReferenceAgent as Agent
    r = run_episode(get_task(name), seed, Agent())
    return {"task": name, "seed": seed, "success": r.success, "primitives": r.primitives, "wall_s": r.wall_s,
            "sim_s": r.sim_s, "goal": r.goal, "error": r.error, "diagnostics": list(r.diagnostics)}


def summarize(name: str, episodes: list[dict]) -> dict:
    n = len(episodes)
    return {
        "n": n,
        "success_rate": sum(e["success"] for e in episodes) / n,
        "mean_primitives": sum(e["primitives"] for e in episodes) / n,
        "mean_wall_s": sum(e["wall_s"] for e in episodes) / n,
        "mean_sim_s": sum(e["sim_s"] for e in episodes) / n,
    }


def main(kind: str, doc: str, argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", default="all", help="names, tags (benchmark, generated) or 'all' (default: all)")
    ap.add_argument("--seeds", type=int, default=50, help="number of test seeds (odd, from 10001)")
    ap.add_argument("--workers", type=int, default=1, help="processes (results do not depend on it)")
    args = ap.parse_args(argv)
    seeds = [10001 + 2 * k for k in range(args.seeds)]
    names = resolve(args.tasks)
    jobs = [(name, seed) for name in names for seed in seeds]
    by_task: dict[str, list[dict]] = {name: [] for name in names}

    def record(ep: dict) -> None:
        by_task[ep["task"]].append(ep)
        print(json.dumps({k: ep[k] for k in ("task", "seed", "success", "primitives", "wall_s", "error")}
                         | {"diagnostics": ep["diagnostics"] if not ep["success"] else []}), file=sys.stderr, flush=True)
        if len(by_task[ep["task"]]) == len(seeds):
            print(json.dumps({"task": ep["task"], **summarize(ep["task"], by_task[ep["task"]])}),
                  file=sys.stderr, flush=True)

    if args.workers > 1:
        with spawn_pool(args.workers) as pool:  # spawn, not the platform's fork: MuJoCo/EGL do not survive it
            futures = [pool.submit(run_one, kind, name, seed) for name, seed in jobs]
            for f in as_completed(futures):
                record(f.result())
    else:
        for name, seed in jobs:
            record(run_one(kind, name, seed))
    per_task = {name: summarize(name, eps) for name, eps in by_task.items()}
    failures = [{k: e[k] for k in ("task", "seed", "goal", "error", "diagnostics")}
                for name in names for e in sorted(by_task[name], key=lambda e: e["seed"]) if not e["success"]]
    n = sum(v["n"] for v in per_task.values())
    overall = sum(v["success_rate"] * v["n"] for v in per_task.values()) / n if n else 0.0
    print(json.dumps({"agent": kind, "seeds": args.seeds, "overall_success_rate": overall,
                      "min_task_success_rate": min((v["success_rate"] for v in per_task.values()), default=0.0),
                      "tasks": per_task, "failures": failures}, indent=1))
    return 0
