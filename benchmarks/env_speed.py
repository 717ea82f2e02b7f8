"""Speed of the learning-agent env and of demonstration generation; prints one JSON object.

* env steps/s with the oracle as policy, without observations (``EnvConfig(cameras=())``) and with
  the default observations (three 640x480 RGB-D views), reset time reported apart;
* oracle demonstrations per minute with ``--workers`` processes (full-size images), bytes per step;
* the PyBullet Ravens oracle figure for comparison (3-4 s per pick-and-place with observations on
  this kind of machine, as stated in issue #16 - quoted, not measured here).

Wall times depend on the machine's load (the 1-minute load average and core count are printed).

    python benchmarks/env_speed.py [--task stack-all-blocks-on-a-zone] [--seeds 3] [--demos 4] [--workers 2]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

from capmj.demos.generate import generate_split, make_pool
from capmj.envs import EnvConfig, TabletopEnv
from capmj.envs.oracle import run_oracle

RAVENS_S_PER_STEP_WITH_OBS = (3.0, 4.0)


def env_speed(task: str, seeds: list[int], config: EnvConfig) -> dict[str, float]:
    steps, step_s, reset_s, wins = 0, 0.0, 0.0, 0
    for seed in seeds:
        env = TabletopEnv(task, seed=seed, config=config)
        t0 = time.perf_counter()
        env.reset()
        t1 = time.perf_counter()
        wins += run_oracle(env) is None
        step_s += time.perf_counter() - t1
        reset_s += t1 - t0
        steps += env.steps
        env.close()
    return {"episodes": len(seeds), "successes": wins, "steps": steps, "steps_per_s": round(steps / step_s, 3),
            "s_per_step": round(step_s / steps, 3), "reset_s_mean": round(reset_s / len(seeds), 3)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--task", default="stack-all-blocks-on-a-zone")
    ap.add_argument("--seeds", type=int, default=3, help="test seeds (odd, from 10001) per env measurement")
    ap.add_argument("--demos", type=int, default=4, help="demonstrations generated for the demos/min figure")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    seeds = [10001 + 2 * k for k in range(args.seeds)]
    out: dict[str, object] = {"task": args.task, "cpus": os.cpu_count(),
                              "load_avg_1min_start": round(os.getloadavg()[0], 2)}
    out["env_no_obs"] = env_speed(args.task, seeds, EnvConfig(cameras=()))
    out["env_obs_3x640x480"] = env_speed(args.task, seeds, EnvConfig())
    with tempfile.TemporaryDirectory() as tmp:
        pool = make_pool(args.workers)
        t0 = time.perf_counter()
        try:
            stats = generate_split(args.task, "val", args.demos, tmp, config=EnvConfig(), workers=args.workers,
                                   pool=pool)
        finally:
            if pool is not None:
                pool.shutdown()
        wall = time.perf_counter() - t0
    out["demos"] = {"workers": args.workers, "saved": stats.saved, "skipped": stats.skipped, "steps": stats.steps,
                    "wall_s": round(wall, 2), "demos_per_min": round(stats.saved / wall * 60, 2),
                    "s_per_step": round(wall / stats.steps, 3), "bytes_per_step": round(stats.bytes_per_step)}
    out["ravens_pybullet_oracle_s_per_step_with_obs"] = list(RAVENS_S_PER_STEP_WITH_OBS)
    out["load_avg_1min_end"] = round(os.getloadavg()[0], 2)
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
