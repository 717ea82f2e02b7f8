"""Why capmj uses analytic UR5e IK refined on the MuJoCo model: a measurement.

Solves the same random top-down suction poses over the workspace with
(1) ``ur-analytic-ik`` + 2–6 Gauss-Newton steps on the real model (what capmj uses),
(2) mink 1.3 (differential IK, daqp), and (3) dm_control's ``qpos_from_site_pose``,
and prints success rate, median / p99 ms per solve and the worst position error as JSON.

    python benchmarks/ik.py [--poses 200] [--seed 0]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from capmj.sim.ik import SuctionIK, tool_rotation
from capmj.sim.objects import ObjectSpec
from capmj.sim.robot import SUCTION_TIP_SITE, robot_source
from capmj.sim.world import World


def summarise(times: list[float], errs: list[float], n: int) -> dict:
    t = np.asarray(times) * 1e3
    return {"success_rate": len(errs) / n, "ms_median": float(np.median(t)), "ms_p99": float(np.percentile(t, 99)),
            "max_pos_error_m": float(max(errs)) if errs else None}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--poses", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    w = World([ObjectSpec(1, "block", "red", (0.5, 0.0, 0.02), 0.0, "small")])
    targets = [(np.array([rng.uniform(0.25, 0.75), rng.uniform(-0.5, 0.5), rng.uniform(0.02, 0.3)]),
                float(rng.uniform(-np.pi, np.pi))) for _ in range(args.poses)]
    q0 = w.arm_q()
    out: dict[str, dict] = {}

    ik = SuctionIK(w.model, w.tip_site, w.arm_qpos, w.arm_dof)
    times, errs = [], []
    for pos, yaw in targets:
        t = time.perf_counter()
        r = ik.solve(pos, yaw, q0)
        times.append(time.perf_counter() - t)
        if r.q is not None:
            errs.append(float(np.linalg.norm(ik.tip_position(r.q) - pos)))
    out["analytic+refine (capmj)"] = summarise(times, errs, len(targets))

    try:
        import mink

        cfg = mink.Configuration(w.model)
        task = mink.FrameTask(SUCTION_TIP_SITE, "site", position_cost=1.0, orientation_cost=1.0, lm_damping=1.0)
        limits = [mink.ConfigurationLimit(w.model)]
        times, errs = [], []
        for pos, yaw in targets:
            q = w.data.qpos.copy()
            cfg.update(q)
            task.set_target(mink.SE3.from_rotation_and_translation(mink.SO3.from_matrix(tool_rotation(yaw)), pos))
            t = time.perf_counter()
            for _ in range(200):
                vel = mink.solve_ik(cfg, [task], 1.0, "daqp", 1e-4, limits=limits)
                cfg.integrate_inplace(vel, 1.0)
                e = task.compute_error(cfg)
                if np.linalg.norm(e[:3]) < 1e-4 and np.linalg.norm(e[3:]) < 1e-3:
                    break
            times.append(time.perf_counter() - t)
            err = float(np.linalg.norm(cfg.data.site_xpos[w.tip_site] - pos))
            if err < 1e-3:
                errs.append(err)
        out["mink 1.3 (daqp)"] = summarise(times, errs, len(targets))
    except Exception as exc:  # noqa: BLE001
        out["mink 1.3 (daqp)"] = {"error": f"{type(exc).__name__}: {exc}"}

    try:
        from dm_control import mujoco as dm_mujoco
        from dm_control.utils.inverse_kinematics import qpos_from_site_pose

        xml = w.xml.replace('meshdir="assets', f'meshdir="{robot_source().xml_path.parent}/assets')
        with tempfile.NamedTemporaryFile("w", suffix=".xml", delete=False) as f:
            f.write(xml)
        physics = dm_mujoco.Physics.from_xml_path(f.name)
        os.unlink(f.name)
        joints = [w.model.joint(int(j)).name for j in w.model.dof_jntid[w.arm_dof]]
        times, errs = [], []
        for pos, yaw in targets:
            quat = np.zeros(4)
            mujoco.mju_mat2Quat(quat, tool_rotation(yaw).reshape(-1))
            physics.data.qpos[:] = w.data.qpos
            t = time.perf_counter()
            r = qpos_from_site_pose(physics, SUCTION_TIP_SITE, pos, quat, joint_names=joints, tol=1e-10, max_steps=200,
                                    inplace=False)
            times.append(time.perf_counter() - t)
            if r.success:
                errs.append(float(r.err_norm))
        out["dm_control qpos_from_site_pose"] = summarise(times, errs, len(targets))
    except Exception as exc:  # noqa: BLE001
        out["dm_control qpos_from_site_pose"] = {"error": f"{type(exc).__name__}: {exc}"}

    print(json.dumps({"poses": args.poses, "solvers": out}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
