"""What the failed-episode thumbnail (capmj.bench.thumbnail) costs a worker, printed as JSON.

    MUJOCO_GL=egl python benchmarks/thumbnail_cost.py [--tasks benchmark] [--seeds 10001:10011:2]

In a fresh spawned process (as a pool worker is): the oracle plays each (task, seed) and its final
poses are drawn as the worker draws a failed episode's thumbnail.  Prints the first thumbnail's
seconds (it creates the process's GL context), the mean and largest of the others, the mean
episode wall time beside them, and the PNG sizes.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path


def measure(tasks: str, seeds: str) -> dict:
    from capmj.agents.oracle import OracleAgent
    from capmj.bench.seeds import parse_seeds
    from capmj.bench.thumbnail import write_thumbnail
    from capmj.runner import run_episode
    from capmj.tasks.registry import get_task, resolve

    thumbs: list[float] = []
    episodes: list[float] = []
    sizes: list[int] = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in resolve(tasks):
            task = get_task(name)
            for seed in parse_seeds(seeds):
                result = run_episode(task, seed, OracleAgent())
                episodes.append(result.wall_s)
                t0 = time.perf_counter()
                path = write_thumbnail(Path(tmp) / f"{name}-{seed}.png", task, seed, result.final_poses)
                thumbs.append(time.perf_counter() - t0)
                sizes.append(path.stat().st_size)
    rest = thumbs[1:] or thumbs
    return {"thumbnails": len(thumbs), "first_s": round(thumbs[0], 3), "mean_s": round(sum(rest) / len(rest), 4),
            "max_s": round(max(rest), 4), "episode_wall_mean_s": round(sum(episodes) / len(episodes), 3),
            "png_bytes_mean": round(sum(sizes) / len(sizes)), "png_bytes_max": max(sizes), "size_px": [320, 160]}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tasks", default="benchmark")
    p.add_argument("--seeds", default="10001:10011:2")
    args = p.parse_args(argv)
    from capmj.bench.pool import spawn_pool

    with spawn_pool(1) as pool:  # a fresh process, as a pool worker
        out = pool.submit(measure, args.tasks, args.seeds).result()
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
