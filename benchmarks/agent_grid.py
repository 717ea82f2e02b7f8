"""Shared runner of ``oracle.py`` and ``reference.py``: one agent over tasks × test seeds.

Prints one JSON object per task to stderr as it finishes and, last, a summary JSON object on
stdout: success rate, mean primitives and wall seconds per task, and every failure with its seed,
goal, error and diagnostics.  Tasks default to every registered task (A–J, the generated tasks and
any installed plugin task); ``--tasks`` takes names, tags or ``all``.
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from functools import partial

from capmj.tasks.registry import get_task, resolve


def make_agent(kind: str):
    if kind == "oracle":
        from capmj.agents.oracle import OracleAgent

        return OracleAgent()
    from capmj.agents.reference import ReferenceAgent

    return ReferenceAgent()


def run_task(kind: str, name: str, seeds: list[int]) -> tuple[dict, list[dict]]:
    from capmj.runner import run_episode

    task, agent = get_task(name), make_agent(kind)
    results = [run_episode(task, s, agent) for s in seeds]
    n = len(results)
    stats = {
        "n": n,
        "success_rate": sum(r.success for r in results) / n,
        "mean_primitives": sum(r.primitives for r in results) / n,
        "mean_wall_s": sum(r.wall_s for r in results) / n,
        "mean_sim_s": sum(r.sim_s for r in results) / n,
    }
    failures = [{"task": name, "seed": r.seed, "goal": r.goal, "error": r.error, "diagnostics": list(r.diagnostics)}
                for r in results if not r.success]
    return stats, failures


def main(kind: str, doc: str, argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", default="all", help="names, tags (benchmark, generated) or 'all' (default: all)")
    ap.add_argument("--seeds", type=int, default=50, help="number of test seeds (odd, from 10001)")
    ap.add_argument("--workers", type=int, default=1, help="processes (results do not depend on it)")
    args = ap.parse_args(argv)
    seeds = [10001 + 2 * k for k in range(args.seeds)]
    names = resolve(args.tasks)
    per_task, failures = {}, []
    work = partial(run_task, kind)
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as pool:
            done = list(pool.map(work, names, [seeds] * len(names)))
    else:
        done = (work(n, seeds) for n in names)
    for name, (stats, fails) in zip(names, done):
        per_task[name] = stats
        failures += fails
        print(json.dumps({"task": name, **stats}), file=sys.stderr, flush=True)
    n = sum(v["n"] for v in per_task.values())
    overall = sum(v["success_rate"] * v["n"] for v in per_task.values()) / n if n else 0.0
    print(json.dumps({"agent": kind, "seeds": args.seeds, "overall_success_rate": overall,
                      "min_task_success_rate": min((v["success_rate"] for v in per_task.values()), default=0.0),
                      "tasks": per_task, "failures": failures}, indent=1))
    return 0
