"""Latency of the planner API's ``get_random_free_pos`` (vectorised grid search) as JSON.

Times ``--queries`` calls over benchmark scenes (test seeds, every benchmark task in turn),
alternating the whole workspace, a quadrant and a reserved target position, and prints the
median, p99 and max in milliseconds.  The original scanned a 2 mm grid in pure Python.

    python benchmarks/free_pose.py [--queries 1000]
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np

from capmj.agents.api.footprints import FREE_CLEARANCE, FREE_GRID_STEP
from capmj.agents.api.planner_api import PlannerAPI
from capmj.runner import start_episode
from capmj.tasks.registry import get_task, resolve


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--queries", type=int, default=1000)
    ap.add_argument("--tasks", default="benchmark")
    args = ap.parse_args(argv)
    names = resolve(args.tasks)
    scenes = []
    for k, name in enumerate(names):
        ctx = start_episode(get_task(name), 10001 + 2 * k)
        scenes.append((PlannerAPI(ctx).functions(), len(ctx.scene.objects)))
    queries = [dict(), dict(area=(0.5, 0.0, 0.75, 0.5)), dict(targ=[0.5, 0.0], r=0.03)]
    times, objects = [], []
    for i in range(args.queries):
        fns, n_obj = scenes[i % len(scenes)]
        kwargs = queries[i % len(queries)]
        t0 = time.perf_counter()
        fns["get_random_free_pos"](**kwargs)
        times.append((time.perf_counter() - t0) * 1e3)
        objects.append(n_obj)
    t = np.asarray(times)
    print(json.dumps({
        "function": "get_random_free_pos", "queries": len(t), "grid_step_m": FREE_GRID_STEP,
        "default_clearance_m": FREE_CLEARANCE, "objects_per_scene": [int(min(objects)), int(max(objects))],
        "median_ms": round(float(np.median(t)), 4), "p99_ms": round(float(np.percentile(t, 99)), 4),
        "max_ms": round(float(t.max()), 4), "mean_ms": round(float(t.mean()), 4),
        "python": platform.python_version(), "machine": platform.machine(),
    }))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
