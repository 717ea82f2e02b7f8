"""Reference-plan success per task over the test split (odd seeds from 10001), through real physics.

The reference plans (``prompts/reference/<task>.py``) run through the same planner API and sandbox
as LLM code, so a failure here is a bug in the API, a plan, a task or the simulator.  Prints one
JSON object per task to stderr as it finishes and, last, a summary JSON object on stdout: success
rate, mean primitives and wall seconds per task, and every failure with its seed, error and
diagnostics.

    python benchmarks/reference.py [--tasks benchmark] [--seeds 50] [--workers 4]
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor

from capmj.tasks.registry import get_task, resolve


def run_task(name: str, seeds: list[int]) -> tuple[dict, list[dict]]:
    from capmj.agents.reference import ReferenceAgent
    from capmj.runner import run_episode

    task, agent = get_task(name), ReferenceAgent()
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


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", default="benchmark", help="names, tags or 'all' (default: benchmark)")
    ap.add_argument("--seeds", type=int, default=50, help="number of test seeds (odd, from 10001)")
    ap.add_argument("--workers", type=int, default=1, help="processes (results do not depend on it)")
    args = ap.parse_args(argv)
    seeds = [10001 + 2 * k for k in range(args.seeds)]
    names = resolve(args.tasks)
    per_task, failures = {}, []
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as pool:
            outcomes = list(pool.map(run_task, names, [seeds] * len(names)))
    else:
        outcomes = (run_task(n, seeds) for n in names)
    for name, (stats, fails) in zip(names, outcomes):
        per_task[name] = stats
        failures += fails
        print(json.dumps({"task": name, **stats}), file=sys.stderr, flush=True)
    n = sum(v["n"] for v in per_task.values())
    overall = sum(v["success_rate"] * v["n"] for v in per_task.values()) / n if n else 0.0
    print(json.dumps({"agent": "reference", "seeds": args.seeds, "overall_success_rate": overall,
                      "min_task_success_rate": min((v["success_rate"] for v in per_task.values()), default=0.0),
                      "tasks": per_task, "failures": failures}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
