"""Accuracy and speed of the built-in perceiver against the truth, over tasks x test seeds.

For each (task, seed) the scene is spawned and settled ("reset"), and optionally solved by the
oracle ("final": stacks, blocks in bowls and zones; the arm is then put back at its home pose,
out of the way, before the pictures are taken); the three cameras are rendered (RGB + depth
only) and :class:`capmj.perception.ClassicalPerceiver` runs on them.  Its detections are matched
one-to-one to the true objects (``capmj.perception.score``: 3-D distance within a 2 cm gate,
same-kind pairs first).  Only this
script and the tests read the truth.

Output: one JSON line per scene on stderr, then a summary JSON object on stdout per state:
recall, precision, kind / colour / size accuracy (over matches; size over blocks), position error
(3-D and xy, median / p95 / max, mm), yaw error (blocks, zones, fixtures; degrees), the colour
confusions as (true, perceived) counts, wall and CPU seconds per perception call, and per task
the same headline figures.

    python benchmarks/perception.py [--tasks all] [--seeds 20] [--states reset,final] [--workers 1]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections import Counter
import numpy as np

from capmj.bench.pool import spawn_pool
from capmj.tasks.registry import resolve


def run_scene(task_name: str, seed: int, states: tuple[str, ...]) -> list[dict]:
    """Score the perceiver on one scene in each requested state."""
    from capmj.agents.oracle import OracleAgent
    from capmj.agents.api.perception_audit import true_objects
    from capmj.perception import ClassicalPerceiver, RGBDBundle
    from capmj.perception.score import score
    from capmj.sim.cameras import CameraRig
    from capmj.runner import start_episode
    from capmj.sim.robot import HOME_QPOS
    from capmj.tasks.registry import get_task

    ctx = start_episode(get_task(task_name), seed)
    world = ctx.world
    perceiver = ClassicalPerceiver()
    rows = []
    with CameraRig(world) as rig:
        for state in states:
            if state == "final":
                OracleAgent().act(ctx)
                # Pictures are taken with the arm out of view, as in Ravens: the oracle leaves the
                # tool 0.2 m over the table, where it would hide (and look like) objects.
                world.set_arm(np.array(HOME_QPOS))
                world.settle()
            bundle = RGBDBundle.from_frames(rig.render_all(seg=False, heightmap=False).views.values())
            wall, cpu = time.perf_counter(), time.process_time()
            detections = perceiver.perceive(bundle)
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
            _, truth = true_objects(world)
            s = score(detections, truth)
            rows.append({"task": task_name, "seed": seed, "state": state, "wall_s": wall, "cpu_s": cpu,
                         **s.to_dict(),
                         "_pos": [m.position_error * 1000 for m in s.matches],
                         "_xy": [m.xy_error * 1000 for m in s.matches],
                         "_yaw": [math.degrees(m.yaw_error) for m in s.matches if m.yaw_error is not None],
                         "_block_matches": sum(truth[m.truth].kind == "block" for m in s.matches)})
    return rows


def _pct(values: list[float], q: float) -> float | None:
    return round(float(np.percentile(values, q)), 2) if values else None


def summarize(rows: list[dict]) -> dict:
    n_true = sum(r["n_true"] for r in rows)
    n_det = sum(r["n_detected"] for r in rows)
    matched = sum(r["matched"] for r in rows)
    blocks = sum(r["_block_matches"] for r in rows)
    pos = [v for r in rows for v in r["_pos"]]
    xy = [v for r in rows for v in r["_xy"]]
    yaw = [v for r in rows for v in r["_yaw"]]
    confusions = Counter(f"{t}->{p}" for r in rows for t, p in r["confusions"])
    return {
        "scenes": len(rows), "objects": n_true, "detections": n_det,
        "recall": round(matched / n_true, 4) if n_true else None,
        "precision": round(matched / n_det, 4) if n_det else None,
        "kind_accuracy": round(1 - sum(r["kind_errors"] for r in rows) / matched, 4) if matched else None,
        "color_accuracy": round(1 - sum(r["color_errors"] for r in rows) / matched, 4) if matched else None,
        "size_accuracy": round(1 - sum(r["size_errors"] for r in rows) / blocks, 4) if blocks else None,
        "pos_mm": {"median": _pct(pos, 50), "p95": _pct(pos, 95), "max": _pct(pos, 100)},
        "xy_mm": {"median": _pct(xy, 50), "p95": _pct(xy, 95), "max": _pct(xy, 100)},
        "yaw_deg": {"median": _pct(yaw, 50), "p95": _pct(yaw, 95), "max": _pct(yaw, 100)},
        "color_confusions": dict(sorted(confusions.items())),
        "seconds_per_call": {"wall_median": _pct([r["wall_s"] for r in rows], 50),
                             "cpu_median": _pct([r["cpu_s"] for r in rows], 50)},
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", default="all", help="names, tags (benchmark, generated) or 'all' (default: all)")
    ap.add_argument("--seeds", type=int, default=20, help="number of test seeds (odd, from 10001)")
    ap.add_argument("--states", default="reset", help="comma list of reset, final (final runs the oracle)")
    ap.add_argument("--workers", type=int, default=1, help="processes (results do not depend on it)")
    args = ap.parse_args(argv)
    states = tuple(s.strip() for s in args.states.split(",") if s.strip())
    if not states or set(states) - {"reset", "final"} or states != tuple(sorted(set(states), key=("reset", "final").index)):
        ap.error("--states takes reset, final or reset,final")
    seeds = [10001 + 2 * k for k in range(args.seeds)]
    jobs = [(name, seed) for name in resolve(args.tasks) for seed in seeds]
    rows: list[dict] = []

    def record(batch: list[dict]) -> None:
        for r in batch:
            rows.append(r)
            print(json.dumps({k: v for k, v in r.items() if not k.startswith("_")}), file=sys.stderr, flush=True)

    if args.workers > 1:
        with spawn_pool(args.workers) as pool:  # spawn, not fork: the workers render with EGL
            for batch in pool.map(run_scene, *zip(*jobs), [states] * len(jobs)):
                record(batch)
    else:
        for name, seed in jobs:
            record(run_scene(name, seed, states))
    out: dict = {"perceiver": "classical", "seeds": args.seeds, "tasks": len({j[0] for j in jobs})}
    for state in states:
        mine = [r for r in rows if r["state"] == state]
        per_task = {}
        for name in dict.fromkeys(r["task"] for r in mine):
            s = summarize([r for r in mine if r["task"] == name])
            per_task[name] = {k: s[k] for k in ("recall", "precision", "kind_accuracy", "color_accuracy", "size_accuracy")} \
                | {"pos_mm_median": s["pos_mm"]["median"], "pos_mm_max": s["pos_mm"]["max"]}
        out[state] = summarize(mine) | {"per_task": per_task}
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
