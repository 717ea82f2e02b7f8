"""Oracle success per task over the test split (odd seeds from 10001), through real physics.

Prints one JSON object per task as it finishes and, last, a summary JSON object with the success
rate, mean primitives and wall seconds per episode for every task, and every failure with its
seed, error and diagnostics.

    python benchmarks/oracle.py [--tasks benchmark] [--seeds 50]
"""

from __future__ import annotations

import argparse
import json
import sys

from capmj.agents.oracle import OracleAgent
from capmj.runner import run_episode
from capmj.tasks.registry import get_task, resolve


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", default="benchmark", help="names, tags or 'all' (default: benchmark)")
    ap.add_argument("--seeds", type=int, default=50, help="number of test seeds (odd, from 10001)")
    args = ap.parse_args(argv)
    seeds = [10001 + 2 * k for k in range(args.seeds)]
    agent = OracleAgent()
    per_task, failures = {}, []
    for name in resolve(args.tasks):
        task = get_task(name)
        results = [run_episode(task, s, agent) for s in seeds]
        wins = sum(r.success for r in results)
        per_task[name] = {
            "n": len(results),
            "success_rate": wins / len(results),
            "mean_primitives": sum(r.primitives for r in results) / len(results),
            "mean_wall_s": sum(r.wall_s for r in results) / len(results),
            "mean_sim_s": sum(r.sim_s for r in results) / len(results),
        }
        for r in results:
            if not r.success:
                failures.append({"task": name, "seed": r.seed, "error": r.error, "diagnostics": list(r.diagnostics)})
        print(json.dumps({"task": name, **per_task[name]}), file=sys.stderr)
    n = sum(v["n"] for v in per_task.values())
    overall = sum(v["success_rate"] * v["n"] for v in per_task.values()) / n if n else 0.0
    print(json.dumps({"seeds": args.seeds, "overall_success_rate": overall,
                      "min_task_success_rate": min((v["success_rate"] for v in per_task.values()), default=0.0),
                      "tasks": per_task, "failures": failures}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
