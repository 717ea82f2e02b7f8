"""Rendering benchmark: ms per frame for each camera (rgb + depth + seg) and the heightmap.

Also each camera as RGB + depth only (``<name>_rgbd_ms``, one pass) and the three views that way
(``all_views_rgbd_ms``), where the code supports it.

Prints one JSON line.  Averages over ``--frames`` frames after one warm-up frame per view; the arm
is moved a little between frames so every frame re-reads the scene.  One-off costs (shared GL
context + MjrContext at the first render) are reported separately as ``init_s``.

    MUJOCO_GL=egl python benchmarks/render.py [--frames 20]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

from capmj.sim.gl import ensure_gl_backend

ensure_gl_backend()  # before mujoco is imported: probes egl, then osmesa, if MUJOCO_GL is unset

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from capmj.sim.cameras import CameraRig  # noqa: E402
from capmj.sim.objects import ObjectSpec  # noqa: E402
from capmj.sim.world import World  # noqa: E402

SPECS = [
    ObjectSpec(1, "block", "red", (0.5, 0.0, 0.02), 0.0, "small"),
    ObjectSpec(2, "block", "blue", (0.4, 0.2, 0.03), 0.3, "big"),
    ObjectSpec(3, "zone", "green", (0.6, -0.2, 0.0005)),
    ObjectSpec(4, "bowl", "yellow", (0.6, 0.25, 0.0175)),
    ObjectSpec(5, "block", "purple", (0.65, -0.35, 0.02), 0.7, "small"),
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=20)
    args = ap.parse_args()
    world = World(SPECS)
    rig = CameraRig(world)
    t0 = time.perf_counter()
    rig.render("front")
    init_s = time.perf_counter() - t0
    jobs = {name: (lambda n=name: rig.render(n)) for name in rig.camera_names}
    jobs["heightmap"] = rig.heightmap
    try:  # RGB + depth in one pass (no segmentation); absent before issue #17
        rig.render("front", seg=False)
        jobs.update({f"{name}_rgbd": (lambda n=name: rig.render(n, seg=False)) for name in rig.camera_names})
        jobs["all_views_rgbd"] = lambda: rig.render_all(seg=False, heightmap=False)
    except TypeError:
        pass
    q0 = world.arm_q()
    result: dict[str, object] = {}
    for name, job in jobs.items():
        job()  # warm-up
        total = 0.0
        for i in range(args.frames):
            world.set_arm(q0 + 0.01 * np.sin(i))
            mujoco.mj_forward(world.model, world.data)
            t = time.perf_counter()
            job()
            total += time.perf_counter() - t
        result[f"{name}_ms"] = round(1000 * total / args.frames, 2)
    t = time.perf_counter()
    for _ in range(args.frames):
        rig.render_all()
    result["render_all_ms"] = round(1000 * (time.perf_counter() - t) / args.frames, 2)
    rig.close()
    print(json.dumps({
        "benchmark": "render", "backend": os.environ.get("MUJOCO_GL"), "frames": args.frames,
        "size": [rig.width, rig.height], "heightmap_size": [rig.hm_cols, rig.hm_rows],
        "init_s": round(init_s, 3), **result, "machine": platform.machine(), "cpus": os.cpu_count(),
    }))


if __name__ == "__main__":
    main()
