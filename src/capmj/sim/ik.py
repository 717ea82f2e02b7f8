"""Inverse kinematics for the suction tip: analytic UR5e IK, refined on the MuJoCo model.

Choice by measurement (see ``benchmarks/ik.py``): ``ur-analytic-ik`` solves a pose in ~20 µs and
returns every branch, so we can pick the one closest to the current joints; its DH parameters differ
from the Menagerie meshes by up to ~1 mm, so two or three damped Gauss-Newton steps on the real
model remove that error (< 0.05 mm).  mink needs ~2.4–4.4 ms per pose and dm_control's
``qpos_from_site_pose`` ~4.8 ms, both iterative from the current seed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from capmj.sim.robot import CUP_LENGTH

def tool_rotation(yaw: float) -> np.ndarray:
    """Rotation of the suction tip frame pointing straight down, rotated by ``yaw`` about world z:
    ``Rz(yaw) @ diag(1, -1, -1)`` written out (the product has exact entries; the IK calls this
    tens of times per line, where numpy's 3 x 3 product cost more than the solver)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])


def arm_inertia_block(model: mujoco.MjModel, data: mujoco.MjData, dofs: slice | np.ndarray) -> np.ndarray:
    """The arm's block of the joint-space inertia matrix (coupling included) from ``data``'s
    composite inertias (after ``mj_crb``, as any step leaves them)."""
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    return full[dofs][:, dofs]


def _as_index(idx: np.ndarray) -> slice | np.ndarray:
    """A slice when the addresses are consecutive (the arm's always are): indexing with it takes a
    view instead of a fancy-indexed copy, a few microseconds per IK iteration."""
    idx = np.asarray(idx, dtype=int)
    if len(idx) and np.array_equal(idx, np.arange(idx[0], idx[0] + len(idx))):
        return slice(int(idx[0]), int(idx[0]) + len(idx))
    return idx


@dataclass(frozen=True)
class IKResult:
    q: np.ndarray | None
    error: float  # position error of the refined solution (m); inf when unreachable
    offset: np.ndarray | None = None
    """Refined minus analytic joints: the analytic model's error here, for seeding a nearby solve."""


class SuctionIK:
    """IK of the suction tip site on one world's model, using a private ``MjData``."""

    def __init__(self, model: mujoco.MjModel, tip_site: int, arm_qpos: np.ndarray, arm_dof: np.ndarray) -> None:
        import ur_analytic_ik

        self._solver = ur_analytic_ik.ur5e
        self.model = model
        self.data = mujoco.MjData(model)
        self.site = tip_site
        self.qadr = _as_index(arm_qpos)
        self.dadr = _as_index(arm_dof)
        self._tcp = np.eye(4)
        self._tcp[2, 3] = CUP_LENGTH
        self.lo = model.jnt_range[[model.dof_jntid[d] for d in arm_dof], 0]
        self.hi = model.jnt_range[[model.dof_jntid[d] for d in arm_dof], 1]
        self._weights = np.array([1.0, 1.0, 1.0, 0.5, 0.5, 0.2])
        self._jacp = np.zeros((3, model.nv))
        self._jacr = np.zeros((3, model.nv))
        self._jac = np.zeros((6, len(arm_dof)))
        self._damping = 1e-6 * np.eye(6)
        self._target = np.eye(4)
        self._quat = np.zeros(4)
        self._e = np.zeros(6)

    def solve(self, pos: np.ndarray, yaw: float, q_near: np.ndarray, tol: float = 1e-4,
              offset: np.ndarray | None = None) -> IKResult:
        """Joints putting the tip at ``pos`` pointing down with ``yaw``, closest to ``q_near``.

        ``offset`` is the :attr:`IKResult.offset` of a solve nearby (a few cm along the same
        line): the analytic model's error changes slowly, so the analytic solution plus that
        offset is usually already within ``tol`` and needs no Gauss-Newton step (``docs/speed.md``),
        where the bare analytic one always needs one.
        """
        q_an = self.solve_analytic(pos, yaw, q_near)
        if q_an is None:
            return IKResult(None, np.inf)
        res = self._refine(q_an if offset is None else q_an + offset, np.asarray(pos, float),
                           self._target[:3, :3].copy(), tol)
        return res if res.q is None else IKResult(res.q, res.error, res.q - q_an)

    def solve_analytic(self, pos: np.ndarray, yaw: float, q_near: np.ndarray) -> np.ndarray | None:
        """The analytic solution nearest ``q_near`` within the joint limits, unrefined (~1 mm off)."""
        target = self._target
        target[:3, :3] = tool_rotation(yaw)
        target[:3, 3] = pos
        sols = self._solver.inverse_kinematics_with_tcp(target, self._tcp)
        if not sols:
            return None
        q = np.array(sols, dtype=float)
        # Joints with 2*pi ranges admit q and q +- 2*pi: take the branch nearest q_near.
        q -= q_near
        q += np.pi
        np.mod(q, 2 * np.pi, out=q)
        q += q_near
        q -= np.pi
        # NaN (a failed branch) fails both comparisons, so this also drops non-finite solutions.
        ok = ((q >= self.lo) & (q <= self.hi)).all(axis=1)
        if not ok.any():
            return None
        dq = q - q_near
        cost = (dq * dq * self._weights).sum(axis=1)
        cost[~ok] = np.inf
        return q[int(np.argmin(cost))]

    def _kinematics(self, q: np.ndarray) -> None:
        """Forward kinematics of joints ``q`` in the private data (the world is untouched)."""
        self.data.qpos[self.qadr] = q
        mujoco.mj_kinematics(self.model, self.data)

    def _jacobian(self) -> np.ndarray:
        """The tip's 6 x 6 arm Jacobian (linear rows, then angular) after :meth:`_kinematics`."""
        m, d, jac = self.model, self.data, self._jac
        mujoco.mj_comPos(m, d)
        mujoco.mj_jacSite(m, d, self._jacp, self._jacr, self.site)
        jac[:3] = self._jacp[:, self.dadr]
        jac[3:] = self._jacr[:, self.dadr]
        return jac

    def arm_inertia(self, q: np.ndarray) -> np.ndarray:
        """The arm's 6 x 6 block of the joint-space inertia matrix at joints ``q`` (coupling
        included), for feed-forward of a motion that starts there (the world is untouched)."""
        m, d = self.model, self.data
        self._kinematics(q)
        mujoco.mj_comPos(m, d)
        mujoco.mj_crb(m, d)
        return arm_inertia_block(m, d, self.dadr)

    def _refine(self, q: np.ndarray, pos: np.ndarray, rot: np.ndarray, tol: float) -> IKResult:
        """Damped Gauss-Newton steps on the MuJoCo model (removes the analytic model's ~1 mm error)."""
        d, site = self.data, self.site
        quat, e = self._quat, self._e
        err = np.inf
        for _ in range(6):
            self._kinematics(q)
            e[:3] = pos - d.site_xpos[site]
            mujoco.mju_mat2Quat(quat, (rot @ d.site_xmat[site].reshape(3, 3).T).ravel())
            mujoco.mju_quat2Vel(e[3:], quat, 1.0)
            ex, ey, ez = e[0], e[1], e[2]
            err = math.sqrt(ex * ex + ey * ey + ez * ez)
            if err < tol and e[3] * e[3] + e[4] * e[4] + e[5] * e[5] < 1e-6:
                break
            jac = self._jacobian()
            q = q + jac.T @ np.linalg.solve(jac @ jac.T + self._damping, e)
        ok = err < 1e-3 and bool((q >= self.lo).all() and (q <= self.hi).all())
        return IKResult(q if ok else None, err)

    def joint_rate(self, q: np.ndarray, lin: np.ndarray, yaw_rate: float) -> np.ndarray:
        """Joint velocity moving the tip at linear velocity ``lin`` while it turns about the
        vertical at ``yaw_rate`` (pointing down throughout): ``J(q)^-1 [lin; 0, 0, yaw_rate]``."""
        self._kinematics(q)
        twist = np.array([lin[0], lin[1], lin[2], 0.0, 0.0, yaw_rate])
        return np.linalg.solve(self._jacobian() + self._damping, twist)

    def pose_error(self, q: np.ndarray, pos: np.ndarray, yaw: float) -> tuple[float, float]:
        """(position error m, orientation error rad) of the tip at joints ``q`` against a
        downward-pointing target (private data; the world is untouched)."""
        d = self.data
        self._kinematics(q)
        x, y, z = d.site_xpos[self.site]
        e_pos = math.sqrt((pos[0] - x) ** 2 + (pos[1] - y) ** 2 + (pos[2] - z) ** 2)
        # angle of the residual rotation R_target R_site^T: its trace = 1 + 2 cos(angle), and the
        # trace of A B^T is the sum of the elementwise product
        trace = float(np.dot(tool_rotation(yaw).ravel(), d.site_xmat[self.site]))
        e_rot = math.acos(min(1.0, max(-1.0, (trace - 1.0) / 2.0)))
        return e_pos, e_rot

    def tip_position(self, q: np.ndarray) -> np.ndarray:
        """Forward kinematics of the tip for joints ``q`` (private data; the world is untouched)."""
        self._kinematics(q)
        return self.data.site_xpos[self.site].copy()
