"""``python -m capmj.demos`` / ``capmj-demos``: oracle demonstrations in the Ravens layout.

Prints one JSON object per ``<task>-<split>`` (saved, skipped, steps, bytes, bytes per step) to
stdout; the progress bar goes to stderr.  Running the same command again resumes.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Sequence

from capmj.demos.dataset import SPLIT_FIRST_SEED
from capmj.demos.collect import collect_split, make_pool
from capmj.envs.tabletop import EnvConfig
from capmj.errors import CapmjError
from capmj.sim.cameras import IMAGE_H, IMAGE_W, VIEW_CAMERAS


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="capmj-demos", description=__doc__.splitlines()[0])
    p.add_argument("--tasks", required=True, help="task names, tags or 'all', comma-separated")
    p.add_argument("--split", required=True, choices=sorted(SPLIT_FIRST_SEED),
                   help="train: seeds 0,2,4,...; val: 1,3,5,...; test: 10001,10003,...")
    p.add_argument("--n", type=int, required=True, help="successful episodes wanted per task")
    p.add_argument("--out", required=True, help="dataset root; episodes go to OUT/<task>-<split>/")
    p.add_argument("--workers", type=int, default=1, help="worker processes (default 1: in-process)")
    p.add_argument("--width", type=int, default=IMAGE_W)
    p.add_argument("--height", type=int, default=IMAGE_H)
    p.add_argument("--fast-robot", action="store_true",
                   help="draw the arm as its collision capsules (faster rendering)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        from capmj.tasks.registry import get_task, resolve

        if args.n < 1:
            raise CapmjError(f"--n must be >= 1, got {args.n}")
        tasks = resolve(args.tasks)
        for name in tasks:
            get_task(name)  # fail early, naming the valid tasks
        config = EnvConfig(cameras=VIEW_CAMERAS, width=args.width, height=args.height,
                           robot_meshes=not args.fast_robot)
    except CapmjError as exc:
        print(f"capmj-demos: error: {exc}", file=sys.stderr)
        return 2
    pool = make_pool(args.workers)
    bar = None
    if not args.no_progress:
        from tqdm import tqdm

        bar = tqdm(total=args.n * len(tasks), file=sys.stderr, unit="ep", dynamic_ncols=True, mininterval=0.5)
    try:
        for name in tasks:
            if bar is not None:
                bar.set_description(f"{name}-{args.split}")
            stats = collect_split(name, args.split, args.n, args.out, config=config, workers=args.workers,
                                   pool=pool, progress=bar.update if bar is not None else None)
            if bar is not None:
                bar.update(stats.resumed_from)
            print(json.dumps(stats.to_dict()), flush=True)
    finally:
        if bar is not None:
            bar.close()
        if pool is not None:
            pool.shutdown(cancel_futures=True)
    return 0
