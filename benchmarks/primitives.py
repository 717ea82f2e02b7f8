"""Pick-and-place and stacking benchmark of the foundation layer (prints JSON; last line = summary).

Random pick-and-places of small and big blocks across the workspace, onto the table or onto other
blocks, in worlds rebuilt every ``--per-world`` trials.  A trial succeeds when the carried block
ends within 1 cm (xy) and 1.5 cm (z) of its target, upright.  Wall time per primitive is measured
without rendering on every trial, and with the three cameras + heightmap rendered once after each
primitive on ``--rendered`` extra trials: RGB + depth of the three views (one pass each, mesh arm),
then everything (segmentation and heightmap too) with the arm's visual meshes and with its
collision capsules (``CameraRig(robot_meshes=False)``).  Speed-ups are against the PyBullet Ravens
oracle with its EGL renderer: ``--ravens FILE`` takes a same-day ``benchmarks/ravens_baseline.py``
JSON (else issue #17's quoted figures).  Like Ravens' per-action time (``env.step`` without
observations: primitive and waiting until static), they compare the ``pick_and_place`` call
(primitive and settling), not the trial's own choice of what to move where.  The stacking part
builds towers of 2–8 small blocks.

    python benchmarks/primitives.py [--trials 1000] [--seed 0] [--ravens ravens.json]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from capmj.sim.primitives import Primitives  # noqa: E402
from capmj.sim.world import World  # noqa: E402
from capmj.tasks import predicates as P  # noqa: E402
from capmj.tasks.spawn import Spawner, free_positions  # noqa: E402

RAVENS_EGL_S = {"fast": 0.92, "slow": 1.14}
"""PyBullet Ravens oracle, EGL renderer on, per pick-and-place without observations, as quoted by
issue #17.  Used only without ``--ravens``; a same-day run of ``benchmarks/ravens_baseline.py``
(``--ravens FILE``) is the honest comparison, since this machine's speed varies from day to day."""
RAVENS_EGL_RENDERED_S = {"fast": 1.30, "slow": 1.85}
"""The same with its three RGB-D cameras rendered after each action."""


def ravens_reference(path: str | None) -> tuple[str, dict[str, float], dict[str, float]]:
    """(source, seconds per action without observations, with them) to compare against: the
    median and mean of a ``ravens_baseline.py`` JSON, or the quoted constants."""
    if path is None:
        return "quoted constants (issue #17)", RAVENS_EGL_S, RAVENS_EGL_RENDERED_S
    with open(path, encoding="utf-8") as f:
        run = json.load(f)
    per = run["per_action_s"]
    pick = ("median", "mean")
    return (f"{path}: ravens_baseline.py, {run.get('renderer')}, hz {run.get('hz')}",
            {k: per["no_obs"][k] for k in pick}, {k: per["with_obs"][k] for k in pick})
COLORS = ["red", "blue", "green", "yellow", "orange", "purple", "pink", "cyan"]


def step_seconds(w: World) -> float:
    """Seconds spent inside ``mj_step`` on this world's data so far, from MuJoCo's own timer (a
    Python wrapper around ``mj_step`` would add its own overhead to the wall time measured)."""
    return float(w.data.timer[mujoco.mjtTimer.mjTIMER_STEP].duration)


def random_world(rng: np.random.Generator) -> World:
    sp = Spawner(rng)
    for k in range(4):
        sp.block(COLORS[k], "small")
    for k in range(4, 6):
        sp.block(COLORS[k], "big")
    return World(sp.objects)


def one_trial(w: World, prims: Primitives, rng: np.random.Generator) -> tuple[bool, float, str, float]:
    """One random pick-and-place: (success, xy placement error, kind, wall seconds of the primitive)."""
    state = w.state()
    tops = {i: i for i in w.movable_ids}
    for i in w.movable_ids:  # objects with something on top cannot be picked or stacked onto
        for j in w.movable_ids:
            if i != j and P.resting_on(state, j, i):
                tops.pop(i, None)
    obj = int(rng.choice(sorted(tops)))
    spec = w.objects_by_id[obj]
    onto = [j for j in tops if j != obj and w.objects_by_id[j].size == "big" and state.pos(j)[2] < 0.1]
    if onto and rng.random() < 0.3:
        base = int(rng.choice(onto))
        target = state.pos(base).copy()
        target[2] = w.top_z(base) + spec.half_extents[2]
        kind = "onto-block"
    else:
        current = [o.moved(state.poses[o.obj_id].pos) for o in w.objects if o.obj_id != obj]
        xy = rng.uniform([0.3, -0.4], [0.7, 0.4])
        try:
            spot = free_positions(current, (xy[0] - 0.1, xy[0] + 0.1, xy[1] - 0.1, xy[1] + 0.1), [spec.footprint_radius], margin=0.0)[0]
        except ValueError:
            spot = free_positions(current, (0.25, 0.75, -0.5, 0.5), [spec.footprint_radius])[0]
        target = np.array([spot[0], spot[1], spec.half_extents[2]])
        kind = "table"
    wall0 = time.perf_counter()
    res = prims.pick_and_place(state.pos(obj), target, float(rng.uniform(-np.pi, np.pi)))
    wall = time.perf_counter() - wall0
    final = np.asarray(w.pose(obj).pos)
    err = float(np.linalg.norm(final[:2] - target[:2]))
    ok = res.ok and res.obj_id == obj and err < 0.01 and abs(final[2] - target[2]) < 0.015 \
        and w.pose(obj).tilt < np.radians(15)
    return ok, err, kind, wall


def stack_trial(height: int, rng: np.random.Generator) -> str | None:
    """Build a tower of ``height`` small blocks on a zone; None if it stands, else why not (the
    failing primitive's status and message, or the stack check's reason)."""
    sp = Spawner(rng)
    zone = sp.zone("gray")
    blocks = [sp.block(COLORS[k % len(COLORS)], "small") for k in range(height)]
    w = World(sp.objects)
    prims = Primitives(w)
    for level, b in enumerate(blocks):
        target = (zone.pos[0], zone.pos[1], 0.02 + 0.04 * level)
        res = prims.pick_and_place(np.asarray(w.pose(b.obj_id).pos), np.array(target), 0.0)
        if not res.ok:
            return f"block {level + 1} from {np.round(res.pick[:2], 3).tolist()}: {res.status} ({res.message})"
    w.settle(1500)
    ok, why = P.is_stack(w.state(), [b.obj_id for b in blocks])
    return None if ok else why


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--trials", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--per-world", type=int, default=25, help="trials before the world is rebuilt")
    ap.add_argument("--rendered", type=int, default=100, help="trials also timed with rendering")
    ap.add_argument("--stack-trials", type=int, default=20, help="towers per height (2..8)")
    ap.add_argument("--ravens", metavar="FILE", help="JSON of benchmarks/ravens_baseline.py run the same day "
                    "(default: the ratios use issue #17's quoted Ravens figures)")
    args = ap.parse_args(argv)
    ravens_source, ravens_plain, ravens_rendered = ravens_reference(args.ravens)
    rng = np.random.default_rng(args.seed)

    successes, errors, kinds, failures = 0, [], {"table": 0, "onto-block": 0}, []
    wall_plain, wall_prim, sim_s, steps = 0.0, 0.0, 0.0, 0
    step_s = 0.0
    w = prims = None
    for t in range(args.trials):
        if t % args.per_world == 0:
            w = random_world(rng)
            w.settle()
            prims = Primitives(w)
        s0, t0, mj0, wall0 = w.steps, w.time, step_seconds(w), time.perf_counter()
        ok, err, kind, wall = one_trial(w, prims, rng)
        wall_plain += time.perf_counter() - wall0
        wall_prim += wall
        step_s += step_seconds(w) - mj0
        steps += w.steps - s0
        sim_s += w.time - t0
        successes += ok
        kinds[kind] += 1
        errors.append(err)
        if not ok:
            failures.append({"trial": t, "kind": kind, "error_m": round(err, 4)})
        print(f"\rtrial {t + 1}/{args.trials} success {successes / (t + 1):.4f}", end="", file=sys.stderr)
    print(file=sys.stderr)
    step_share = step_s / wall_plain if wall_plain else 0.0

    rendered: dict[str, float | None] = {}
    render_note = None
    modes = (("mesh_arm_rgbd", True, {"seg": False, "heightmap": False}),  # RGB + depth of the 3 views
             ("mesh_arm", True, {}), ("capsule_arm", False, {}))          # + segmentation + heightmap
    for label, meshes, what in modes if args.rendered > 0 else ():
        try:
            from capmj.sim.cameras import CameraRig

            w = random_world(rng)
            w.settle()
            prims, rig = Primitives(w), CameraRig(w, robot_meshes=meshes)
            rig.render_all(**what)  # warm-up: GL context, mesh upload (one-off costs, see render.py)
            wall = 0.0
            for _ in range(args.rendered):  # the primitive and the rendering after it
                wall += one_trial(w, prims, rng)[3]
                t0 = time.perf_counter()
                rig.render_all(**what)
                wall += time.perf_counter() - t0
            rig.close()
            rendered[label] = wall / args.rendered
        except Exception as exc:  # noqa: BLE001 - report, don't hide the other figures
            render_note = f"{label}: {type(exc).__name__}: {exc}"
            rendered[label] = None

    stack, stack_failures = {}, []
    for h in range(2, 9) if args.stack_trials > 0 else ():
        whys = [stack_trial(h, rng) for _ in range(args.stack_trials)]
        stack[str(h)] = whys.count(None) / args.stack_trials
        stack_failures += [{"height": h, "trial": k, "why": why} for k, why in enumerate(whys) if why is not None]
        print(f"stack height {h}: {stack[str(h)]:.2f}", file=sys.stderr)

    err = np.asarray(errors)
    summary = {
        "trials": args.trials,
        "seed": args.seed,
        "success_rate": successes / args.trials,
        "placements": kinds,
        "placement_error_m_median": float(np.median(err)),
        "placement_error_m_p99": float(np.percentile(err, 99)),
        "wall_s_per_primitive": wall_plain / args.trials,
        "wall_s_per_pick_and_place_call": wall_prim / args.trials,
        "wall_s_per_primitive_rendered_rgbd": rendered.get("mesh_arm_rgbd"),
        "wall_s_per_primitive_rendered": rendered.get("mesh_arm"),
        "wall_s_per_primitive_rendered_capsule_arm": rendered.get("capsule_arm"),
        "rendered_trials": args.rendered,
        "render_error": render_note,
        "sim_s_per_primitive": sim_s / args.trials,
        "physics_steps_per_s": steps / wall_plain,
        "mj_step_share_of_wall": step_share,
        "ravens_egl_source": ravens_source,
        "ravens_egl_s": ravens_plain,
        "ravens_egl_rendered_s": ravens_rendered,
        "speedup_vs_ravens_egl": {k: round(v / (wall_prim / args.trials), 1) for k, v in ravens_plain.items()},
        "speedup_vs_ravens_egl_rendered_rgbd": (
            {k: round(v / rendered["mesh_arm_rgbd"], 1) for k, v in ravens_rendered.items()}
            if rendered.get("mesh_arm_rgbd") else None),
        "stack_success_by_height": stack,
        "stack_trials_per_height": args.stack_trials,
        "stack_failures": stack_failures,
        "failures": failures[:20],
    }
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
