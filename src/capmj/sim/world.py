"""The live MuJoCo world of one episode: model, data, suction, object poses, reset.

``World`` owns the only ``MjModel``/``MjData`` pair of an episode, and it is the only door to them
above ``sim/``: higher layers read object poses through :meth:`World.state` snapshots, body poses,
geom parts, robot links and meshes through the read methods below (plain arrays and the frozen
records of :mod:`capmj.sim.parts`), and act through the motion primitives.  ``model`` and ``data``
stay public for ``sim/`` itself, tests and benchmarks; ``tests/test_layers.py`` keeps the package
above ``sim/`` off them.  The planner never sees this class (it gets the API facade in
``capmj.agents``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import mujoco
import numpy as np

from capmj.sim import parts
from capmj.sim.objects import ObjectSpec
from capmj.sim.robot import ARM_JOINTS, HOME_QPOS, SUCTION_BODY, SUCTION_CUP_GEOM, SUCTION_TIP_SITE
from capmj.sim.scene import compile_scene
from capmj.sim.state import Pose, SceneState
from capmj.sim.suction import Suction, contact_owners

FrameListener = Callable[["World"], None]

ARM_CTRL = slice(0, len(ARM_JOINTS))
"""The arm's six servo references in ``data.ctrl`` (the suction weld is an equality, not an actuator)."""

_NEVER = 2**62
"""A step count no episode reaches: when no frame listener is due."""


@dataclass(frozen=True)
class WorldSnapshot:
    """Full physics state plus the suction weld data (which lives in the *model*)."""

    physics: np.ndarray
    eq_data: np.ndarray
    steps: int


class World:
    """One episode's MuJoCo world built from object specs.

    Deterministic: the same specs give the same model, and MuJoCo's CPU stepping is deterministic,
    so the world evolves identically on every run and process.
    """

    def __init__(self, objects: Sequence[ObjectSpec]) -> None:
        compiled = compile_scene(objects)
        self.model: mujoco.MjModel = compiled.model
        self.data: mujoco.MjData = mujoco.MjData(self.model)
        self.objects: tuple[ObjectSpec, ...] = compiled.objects
        self._compiled = compiled
        m = self.model
        self.objects_by_id = {o.obj_id: o for o in self.objects}
        """Every object's spec by its id, in ``objects`` order (a dict; ``Scene.by_id`` is a method)."""
        self.body_of = {o.obj_id: m.body(o.body).id for o in self.objects}
        self.arm_qpos = np.array([m.jnt_qposadr[m.joint(j).id] for j in ARM_JOINTS])
        self.arm_dof = np.array([m.jnt_dofadr[m.joint(j).id] for j in ARM_JOINTS])
        self.tip_site = m.site(SUCTION_TIP_SITE).id
        self.cup_geom = m.geom(SUCTION_CUP_GEOM).id
        body_to_obj = {b: i for i, b in self.body_of.items()}
        self.geom_obj = np.array([body_to_obj.get(int(b), 0) for b in m.geom_bodyid], dtype=int)
        """Object id of every geom (0 for robot, table and floor)."""
        order = np.argsort(self.geom_obj, kind="stable")
        self._box_geoms = order[self.geom_obj[order] > 0]  # object geoms, grouped by object id
        self._box_ids, self._box_starts = np.unique(self.geom_obj[self._box_geoms], return_index=True)
        self.movable_ids = tuple(o.obj_id for o in self.objects if not o.fixed)
        self.free_qpos = {i: int(m.jnt_qposadr[m.body_jntadr[self.body_of[i]]]) for i in self.movable_ids}
        self.free_dof = {i: int(m.jnt_dofadr[m.body_jntadr[self.body_of[i]]]) for i in self.movable_ids}
        self.weld_of = {i: m.equality(f"suction_{self.objects_by_id[i].body}").id for i in self.movable_ids}
        self.steps = 0
        self._listeners: list[tuple[FrameListener, int]] = []
        self._next_notify = _NEVER  # the step count at which the next listener is due
        self.set_arm(np.array(HOME_QPOS))
        mujoco.mj_forward(m, self.data)
        self.suction = Suction(m, self.data, suction_body=m.body(SUCTION_BODY).id, cup_geom=self.cup_geom,
                               geom_obj=self.geom_obj, body_of=self.body_of, weld_of=self.weld_of)

    @property
    def xml(self) -> str:
        """The compiled scene as MJCF (same specs -> identical text)."""
        return self._compiled.xml

    # ------------------------------------------------------------------ stepping
    @property
    def time(self) -> float:
        return float(self.data.time)

    def set_arm(self, q: np.ndarray) -> None:
        """Teleport the arm (initialisation only) and hold it there with the servos."""
        self.data.qpos[self.arm_qpos] = q
        self.data.qvel[self.arm_dof] = 0.0
        self.set_arm_ctrl(q)

    def arm_q(self) -> np.ndarray:
        return self.data.qpos[self.arm_qpos].copy()

    def arm_ctrl(self) -> np.ndarray:
        """A copy of the arm's servo references (where the servos hold it, not where it is)."""
        return self.data.ctrl[ARM_CTRL].copy()

    def set_arm_ctrl(self, q: np.ndarray) -> None:
        """Set the arm's six servo references: the one place they are written, but for the tight
        loop of :meth:`step_controls`."""
        self.data.ctrl[ARM_CTRL] = q

    def step(self, n: int = 1) -> None:
        """Advance physics ``n`` steps, notifying frame listeners at their own stride."""
        m, d = self.model, self.data
        for _ in range(n):
            mujoco.mj_step(m, d)
            self.steps += 1
            if self.steps >= self._next_notify:
                self._notify()

    def _notify(self) -> None:
        """Call the frame listeners whose stride the step counter has just reached."""
        for fn, every in self._listeners:
            if self.steps % every == 0:
                fn(self)
        self._schedule()

    def _schedule(self) -> None:
        """When the next listener is due: the stepping loops compare one integer per step instead
        of taking every listener's modulo (a third of the per-step Python cost when logging)."""
        self._next_notify = min((((self.steps // every) + 1) * every for _, every in self._listeners),
                                default=_NEVER)

    def step_controls(self, ctrl: np.ndarray, stop: Callable[[], bool] | None = None) -> tuple[int, bool]:
        """One physics step per row of ``ctrl`` (the arm's six servo references); stops after the
        step on which ``stop()`` turns true.  Returns (steps taken, stopped).

        The same steps as ``set_arm_ctrl(row); step()`` per row, in one tight loop: motion
        tracking spends most of an episode here, and the per-step Python work is what it costs
        beyond the physics (so it writes through a view, not the setter).
        """
        m, d, mj_step = self.model, self.data, mujoco.mj_step
        arm = d.ctrl[ARM_CTRL]
        steps = 0
        for row in ctrl:
            arm[:] = row
            mj_step(m, d)
            steps += 1
            self.steps += 1
            if self.steps >= self._next_notify:
                self._notify()
            if stop is not None and stop():
                return steps, True
        return steps, False

    def add_frame_listener(self, fn: FrameListener, every_steps: int = 25) -> None:
        """Call ``fn(world)`` every ``every_steps`` physics steps (e.g. to log transforms)."""
        self._listeners.append((fn, max(1, int(every_steps))))
        self._schedule()

    def max_object_speed(self) -> float:
        if not self.movable_ids:
            return 0.0
        dofs = np.concatenate([np.arange(self.free_dof[i], self.free_dof[i] + 3) for i in self.movable_ids])
        return float(np.max(np.abs(self.data.qvel[dofs])))

    def settle(self, max_steps: int = 1500, tol: float = 0.005, check_every: int = 10) -> int:
        """Step until every movable object moves slower than ``tol`` m/s; returns steps used."""
        used = 0
        while used < max_steps:
            self.step(check_every)
            used += check_every
            if self.max_object_speed() < tol:
                break
        return used

    # ------------------------------------------------------------------ reading
    def tip_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Suction tip position and rotation matrix."""
        d = self.data
        return d.site_xpos[self.tip_site].copy(), d.site_xmat[self.tip_site].reshape(3, 3).copy()

    def pose(self, obj_id: int) -> Pose:
        b = self.body_of[obj_id]
        return Pose.of(self.data.xpos[b], self.data.xquat[b])

    @property
    def link_names(self) -> tuple[str, ...]:
        """The robot's bodies (every body but the world body and the objects), in model order."""
        m, objects = self.model, {o.body for o in self.objects}
        return tuple(n for n in (m.body(i).name for i in range(1, m.nbody)) if n and n not in objects)

    def body_index(self, names: Sequence[str]) -> np.ndarray:
        """Body ids of named bodies (objects' ``body`` names or links), for :meth:`body_poses`."""
        return np.array([self.model.body(n).id for n in names], dtype=np.intp)

    def body_poses(self, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World positions (n, 3) and orientations (n, 4; w, x, y, z) of bodies by id, now (copies)."""
        return self.data.xpos[ids], self.data.xquat[ids]

    def body_parts(self, body: str) -> tuple[parts.GeomPart, ...]:
        """The geoms of a body (an object's ``body`` name or a link), in the body's frame."""
        return parts.body_parts(self.model, self.model.body(body).id)

    def geom_part(self, geom: int) -> parts.GeomPart:
        """One geom by id (e.g. ``cup_geom``), in its body's frame."""
        return parts.geom_part(self.model, geom)

    def link(self, name: str) -> parts.Link:
        """A robot body's parent, joint count and pose in its parent."""
        return parts.link(self.model, name)

    def mesh(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Vertices and triangles of the mesh of a mesh geom (``GeomPart.mesh``)."""
        return parts.mesh(self.model, index)

    @property
    def mesh_size(self) -> tuple[int, int]:
        """Vertices and triangles of all the model's meshes together (a cheap key for mesh caches)."""
        return int(self.model.nmeshvert), int(self.model.nmeshface)

    def state(self) -> SceneState:
        return SceneState(self.objects, {i: self.pose(i) for i in self.objects_by_id}, self.time, self.suction.held)

    def top_z(self, obj_id: int) -> float:
        """World z of the highest point of an object (its axis-aligned box top)."""
        return float(self.aabb(obj_id)[1][2])

    def aabb(self, obj_id: int) -> tuple[np.ndarray, np.ndarray]:
        """World axis-aligned bounding box (min corner, max corner) of an object's geoms."""
        ids, lo, hi = self.object_boxes()
        k = int(np.searchsorted(ids, obj_id))
        if k == len(ids) or ids[k] != obj_id:
            return np.full(3, np.inf), np.full(3, -np.inf)
        return lo[k], hi[k]

    def object_boxes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every object's world axis-aligned bounding box at once: (ids ascending, min corners,
        max corners), from its geoms' own boxes.  Motion asks for all of them several times per
        primitive (transit heights, surfaces under a point), where one object at a time cost
        ~50 µs each."""
        m, d, g = self.model, self.data, self._box_geoms
        if not len(g):
            return self._box_ids, np.empty((0, 3)), np.empty((0, 3))
        rot = d.geom_xmat[g].reshape(-1, 3, 3)
        centre = d.geom_xpos[g] + np.einsum("gij,gj->gi", rot, m.geom_aabb[g, :3])
        ext = np.einsum("gij,gj->gi", np.abs(rot), m.geom_aabb[g, 3:])
        return (self._box_ids, np.minimum.reduceat(centre - ext, self._box_starts),
                np.maximum.reduceat(centre + ext, self._box_starts))

    def contacts_of(self, obj_id: int) -> set[int]:
        """Ids of what touches an object: other object ids, 0 for table/floor/robot, -1 for the cup."""
        return contact_owners(self.data, self.geom_obj, self.cup_geom, obj_id)

    def place_objects(self, poses: Mapping[int, Pose]) -> None:
        """Put movable objects at the given poses, at rest (set-up only, never during an episode).

        For building labelled final states (``capmj.judge``): the caller settles the world
        afterwards, so what a reporter is shown is a resting physical state, not a teleported one.
        Fixed objects cannot be placed; an id that is not movable raises ``KeyError``.
        """
        for obj_id, pose in poses.items():
            if obj_id not in self.free_qpos:
                raise KeyError(f"object {obj_id} is not movable; movable objects: {list(self.movable_ids)}")
            q, v = self.free_qpos[obj_id], self.free_dof[obj_id]
            self.data.qpos[q:q + 3] = pose.pos
            self.data.qpos[q + 3:q + 7] = pose.quat
            self.data.qvel[v:v + 6] = 0.0
        mujoco.mj_forward(self.model, self.data)

    # ------------------------------------------------------------------ reset
    def snapshot(self) -> WorldSnapshot:
        spec = mujoco.mjtState.mjSTATE_INTEGRATION
        buf = np.empty(mujoco.mj_stateSize(self.model, spec))
        mujoco.mj_getState(self.model, self.data, buf, spec)
        return WorldSnapshot(buf, self.model.eq_data.copy(), self.steps)

    def restore(self, snap: WorldSnapshot) -> None:
        """Return to a snapshot exactly (used to reset to the episode's initial state on re-plan)."""
        mujoco.mj_setState(self.model, self.data, snap.physics, mujoco.mjtState.mjSTATE_INTEGRATION)
        self.model.eq_data[:] = snap.eq_data
        self.steps = snap.steps
        self._schedule()
        self.suction.sync()
        mujoco.mj_forward(self.model, self.data)
