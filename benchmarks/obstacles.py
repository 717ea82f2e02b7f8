"""Obstacle benchmark of motion planning (#48 item 1): prints one JSON object.

Random scenes with an obstacle between a pick point and a place point — a tower of 3–7 small or
big blocks, a bowl or an L-fixture, anywhere along the way (also right next to either end) — plus
two loose blocks elsewhere.  Each scene is run twice from the same start, with planning off (the
straight motion of before: ``MotionConfig(plan_collisions=False)``) and on:

- ``pick_and_place``: one primitive from the pick point to the place point;
- ``low_move``: the tool moved, as a low-level move (``Motion.move_to_pose``), 12 cm above the
  table from 13 cm before the obstacle's centre to 13 cm past it, along the pick-to-place
  direction: straight across it.

A *disturbance* is an object other than the carried one that ends (after settling) more than 5 mm
from where it was; ``control`` counts those of the same scene left alone for as long, so a tower
that falls by itself is not blamed on the arm.  Per primitive: wall seconds (median, p95) with
planning off and on, and the seconds spent checking and planning.  Last, the oracle over every
task × ``--oracle-seeds`` test seeds with planning off and on (each episode twice in a row, as the
machine's load drifts): success and the episode's cost (wall and simulated seconds).

    nice python benchmarks/obstacles.py [--scenes 200] [--seed 0] [--oracle-seeds 3] > benchmarks/results/obstacles.json
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import os
import sys
import time
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402

from capmj.errors import MotionPlanningError  # noqa: E402
from capmj.sim.motion_config import MotionConfig  # noqa: E402
from capmj.sim.objects import BLOCK_SIZES, ObjectSpec  # noqa: E402
from capmj.sim.primitives import Primitives  # noqa: E402
from capmj.sim.world import World  # noqa: E402

DISTURBED_M = 0.005
LOW_MOVE_Z = 0.12
LOW_MOVE_HALF = 0.13
"""m either side of the obstacle's centre where the low-level move starts and ends (clear of it)."""
KINDS = ("tower", "bowl", "fixture")


def scene(rng: np.random.Generator) -> tuple[str, list[ObjectSpec], np.ndarray, np.ndarray, np.ndarray]:
    """(obstacle description, objects, pick xy, place xy, obstacle centre xy): block 1 at the pick
    point, the obstacle between pick and place, two loose small blocks elsewhere."""
    while True:
        pick = np.array([rng.uniform(0.3, 0.7), rng.uniform(-0.4, 0.4)])
        place = np.array([rng.uniform(0.3, 0.7), rng.uniform(-0.4, 0.4)])
        if np.linalg.norm(place - pick) < 0.3:
            continue
        kind = KINDS[int(rng.integers(len(KINDS)))]
        u = rng.uniform(0.2, 0.8)
        d = (place - pick) / np.linalg.norm(place - pick)
        centre = pick + u * (place - pick) + rng.uniform(-0.05, 0.05) * np.array([-d[1], d[0]])
        reach = 0.075 if kind != "tower" else 0.06
        if min(np.linalg.norm(centre - pick), np.linalg.norm(centre - place)) < reach + 0.03:
            continue
        objs = [ObjectSpec(1, "block", "red", (float(pick[0]), float(pick[1]), 0.02), size="small")]
        if kind == "tower":
            n, size = int(rng.integers(3, 8)), ("small", "big")[int(rng.integers(2))]
            h = BLOCK_SIZES[size]
            objs += [ObjectSpec(2 + k, "block", "blue", (float(centre[0]), float(centre[1]), h / 2 + k * h), size=size)
                     for k in range(n)]
            what = f"tower of {n} {size}"
        elif kind == "bowl":
            objs.append(ObjectSpec(2, "bowl", "green", (float(centre[0]), float(centre[1]), 0.0175)))
            what = "bowl"
        else:
            objs.append(ObjectSpec(2, "fixture", "yellow", (float(centre[0]), float(centre[1]), 0.02),
                                   yaw=float(rng.uniform(-math.pi, math.pi))))
            what = "fixture"
        loose = []
        for _ in range(100):
            xy = np.array([rng.uniform(0.3, 0.7), rng.uniform(-0.4, 0.4)])
            if min(np.linalg.norm(xy - p) for p in (pick, place, centre, *loose)) > 0.12:
                loose.append(xy)
            if len(loose) == 2:
                break
        base = max(o.obj_id for o in objs) + 1
        objs += [ObjectSpec(base + k, "block", "orange", (float(xy[0]), float(xy[1]), 0.02), size="small")
                 for k, xy in enumerate(loose)]
        return what, objs, pick, place, centre


def disturbed(w: World, before: dict[int, np.ndarray], carried: int | None) -> list[int]:
    w.settle(1000)
    return [i for i, p in before.items() if i != carried and np.linalg.norm(np.asarray(w.pose(i).pos) - p) > DISTURBED_M]


def run_scene(objs: list[ObjectSpec], pick: np.ndarray, place: np.ndarray, centre: np.ndarray, plan: bool,
              seed: int) -> dict[str, Any]:
    out: dict[str, Any] = {}
    # the primitive
    w = World(objs)
    w.settle()
    before = {i: np.asarray(w.pose(i).pos).copy() for i in w.movable_ids}
    arm = Primitives(w, MotionConfig(plan_collisions=plan), seed=seed)
    t0 = time.perf_counter()
    res = arm.pick_and_place(pick, place)
    wall = time.perf_counter() - t0
    out["pick_and_place"] = {"status": res.status, "wall_s": wall, "planning_s": arm.motion.planning_s,
                             "planned_moves": len(res.planned), "steps": res.steps,
                             "disturbed": disturbed(w, before, res.obj_id if res.ok else None)}
    # a low-level move straight across the obstacle
    w = World(objs)
    w.settle()
    before = {i: np.asarray(w.pose(i).pos).copy() for i in w.movable_ids}
    arm = Primitives(w, MotionConfig(plan_collisions=plan), seed=seed)
    d = (place - pick) / np.linalg.norm(place - pick)
    a, b = centre - LOW_MOVE_HALF * d, centre + LOW_MOVE_HALF * d
    status = "ok"
    t0 = time.perf_counter()
    try:
        for xy in (a, b):
            status = arm.motion.move_to_pose(np.array([xy[0], xy[1], LOW_MOVE_Z]), 0.0)[0]
            if status != "ok":
                break
    except MotionPlanningError:
        status = "no_path"
    out["low_move"] = {"status": status, "wall_s": time.perf_counter() - t0, "planning_s": arm.motion.planning_s,
                       "planned_moves": sum(p.planned for p in arm.motion.paths),
                       "disturbed": disturbed(w, before, None)}
    return out


def control(objs: list[ObjectSpec], steps: int) -> list[int]:
    """Objects that move more than 5 mm in a scene nobody touches, over ``steps`` physics steps."""
    w = World(objs)
    w.settle()
    before = {i: np.asarray(w.pose(i).pos).copy() for i in w.movable_ids}
    w.step(steps)
    return disturbed(w, before, None)


def quantiles(xs: list[float]) -> dict[str, float]:
    a = np.asarray(xs, float)
    return {"median": float(np.median(a)), "p95": float(np.percentile(a, 95)), "mean": float(a.mean())} if len(a) else {}


def summarise(rows: list[dict[str, Any]], part: str) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for mode in ("off", "on"):
        rs = [r[mode][part] for r in rows]
        statuses: dict[str, int] = {}
        for r in rs:
            statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        out[mode] = {
            "scenes_with_disturbance": sum(bool(r["disturbed"]) for r in rs),
            "objects_disturbed": sum(len(r["disturbed"]) for r in rs),
            "status": statuses,
            "wall_s": quantiles([r["wall_s"] for r in rs]),
            "planning_s": quantiles([r["planning_s"] for r in rs]),
            "with_planned_moves": sum(r["planned_moves"] > 0 for r in rs),
        }
    out["on_off_median_wall_ratio"] = out["on"]["wall_s"]["median"] / out["off"]["wall_s"]["median"]
    # what planning costs in outcomes: refused (no_path) where the straight motion disturbed
    # nothing, and succeeded only with planning
    out["refused_where_straight_was_harmless"] = sum(
        r["on"][part]["status"] == "no_path" and r["off"][part]["status"] == "ok" and not r["off"][part]["disturbed"]
        for r in rows)
    out["refused_where_straight_disturbed"] = sum(
        r["on"][part]["status"] == "no_path" and bool(r["off"][part]["disturbed"]) for r in rows)
    out["ok_without_disturbance"] = {mode: sum(r[mode][part]["status"] == "ok" and not r[mode][part]["disturbed"]
                                               for r in rows) for mode in ("off", "on")}
    # the disturbances planning removed and the ones it left, by kind of obstacle
    by_kind: dict[str, dict[str, int]] = {}
    for r in rows:
        k = by_kind.setdefault(r["obstacle"].split(" of ")[0], {"scenes": 0, "disturbed_off": 0, "disturbed_on": 0})
        k["scenes"] += 1
        k["disturbed_off"] += bool(r["off"][part]["disturbed"])
        k["disturbed_on"] += bool(r["on"][part]["disturbed"])
    out["by_obstacle"] = by_kind
    return out


def oracle_grid(seeds: list[int]) -> dict[str, Any]:
    """The oracle over every benchmark task × ``seeds`` with planning off, then on."""
    import capmj.sim.motion as motion_module
    from capmj.agents.oracle import OracleAgent
    from capmj.runner import run_episode
    from capmj.tasks.registry import get_task, resolve

    names = resolve("all")
    eps: dict[str, list[dict[str, Any]]] = {"off": [], "on": []}
    try:
        for name in names:
            for seed in seeds:
                for mode, plan in (("off", False), ("on", True)):  # interleaved: the machine's load drifts
                    # Motion makes its MotionConfig() when none is given (as an episode's does): switch its default.
                    motion_module.MotionConfig = functools.partial(MotionConfig, plan_collisions=plan)  # type: ignore[misc]
                    t0 = time.perf_counter()
                    r = run_episode(get_task(name), seed, OracleAgent())
                    eps[mode].append({"task": name, "seed": seed, "success": r.success,
                                      "wall_s": time.perf_counter() - t0, "sim_s": r.sim_s,
                                      "primitives": r.primitives, "error": r.error})
    finally:
        motion_module.MotionConfig = MotionConfig  # type: ignore[misc]
    out: dict[str, Any] = {}
    for mode, es in eps.items():
        out[mode] = {"episodes": len(es), "success": sum(e["success"] for e in es),
                     "wall_s_per_episode": quantiles([e["wall_s"] for e in es]),
                     "sim_s_per_episode": quantiles([e["sim_s"] for e in es]),
                     "primitives": sum(e["primitives"] for e in es),
                     "failures": [e for e in es if not e["success"]]}
    out["wall_ratio_mean"] = out["on"]["wall_s_per_episode"]["mean"] / out["off"]["wall_s_per_episode"]["mean"]
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--oracle-seeds", type=int, default=3, help="test seeds 10001, 10003, ... per task (0: skip)")
    args = ap.parse_args(argv)
    rows = []
    t_start = time.perf_counter()
    for k in range(args.scenes):
        rng = np.random.default_rng([args.seed, k])
        what, objs, pick, place, centre = scene(rng)
        row: dict[str, Any] = {"scene": k, "obstacle": what, "pick": pick.round(3).tolist(), "place": place.round(3).tolist()}
        for mode, plan in (("off", False), ("on", True)):
            row[mode] = run_scene(objs, pick, place, centre, plan, seed=args.seed * 100003 + k)
        row["control"] = control(objs, max(row["off"]["pick_and_place"]["steps"], 1) + 2000)
        rows.append(row)
        print(json.dumps({"scene": k, "obstacle": what,
                          "off": {p: (row["off"][p]["status"], row["off"][p]["disturbed"]) for p in ("pick_and_place", "low_move")},
                          "on": {p: (row["on"][p]["status"], row["on"][p]["disturbed"]) for p in ("pick_and_place", "low_move")},
                          "control": row["control"]}), file=sys.stderr, flush=True)
    result: dict[str, Any] = {
        "benchmark": "obstacles",
        "scenes": args.scenes,
        "seed": args.seed,
        "disturbed_m": DISTURBED_M,
        "control_scenes_with_motion": sum(bool(r["control"]) for r in rows),
        "pick_and_place": summarise(rows, "pick_and_place"),
        "low_move": summarise(rows, "low_move"),
        "disturbed_scenes": [{"scene": r["scene"], "obstacle": r["obstacle"], "pick": r["pick"], "place": r["place"],
                              "on": {p: (r["on"][p]["status"], r["on"][p]["disturbed"]) for p in ("pick_and_place", "low_move")}}
                             for r in rows if r["on"]["pick_and_place"]["disturbed"] or r["on"]["low_move"]["disturbed"]],
        "scenes_s": time.perf_counter() - t_start,
    }
    if args.oracle_seeds:
        result["oracle"] = oracle_grid([10001 + 2 * i for i in range(args.oracle_seeds)])
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
