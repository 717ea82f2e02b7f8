"""Collision checking of arm configurations on MuJoCo's own collision detection.

A :class:`CollisionChecker` owns a scratch copy of the world's model and data: a configuration is
checked by writing the arm's joints there, running forward kinematics, moving the carried object
rigidly with the suction body, and asking ``mj_collision`` for contacts.  The live world is never
touched, so checking a whole path costs no physics step.

What counts: the *moving* geoms (the arm's collision geoms, the suction cup and the carried
object's geoms) against the *static* ones (the table and every object not carried).  The scratch
model's contact bits are set so that only such pairs are ever tested (static-static contacts such
as a block resting on another are not computed at all; the arm's own links are kept apart by its
joint limits and are not checked).  Every moving geom gets a margin of ``clearance``: a pair
closer than that is a collision, so a path keeps that much room where nothing is meant to touch.

What is meant to touch is the caller's :class:`Allowance`: the pairs already touching where the
move starts (the carried object on its support at a lift, the cup on the object it just let go),
and for a guarded descent the objects under where it ends (the object being picked, the surface
being placed on), which only the cup and the carried object may touch.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass

import mujoco
import numpy as np

from capmj.sim.robot import ARM_BODIES, ARM_JOINTS, SUCTION_BODY
from capmj.sim.world import World

CLEARANCE = 0.005
"""m: room kept between a moving geom and a static one where they are not meant to touch."""

CHECK_STEP = 0.01
"""rad: the largest change of any joint between two configurations checked along a path near an
obstacle (about 8 mm at the tool for the base joint at full reach: less than a block's half
edge); in free space the checks are farther apart (:meth:`CollisionChecker.path_collision`)."""

LOOKAHEAD = 0.05
"""m: contacts are computed this far out (the moving geoms' margin in the scratch model), so a
check also says how far the nearest obstacle is, and a path is checked in steps that long."""

TOUCH_TOL = 0.001
"""m: how deep a near contact of the tool may be under :attr:`Allowance.tool_near` (MuJoCo's contact
distance of two resting faces is a fraction of a millimetre)."""

TABLE = 0
"""The owner id of the table (the floor plane) in an :class:`Allowance`."""

_STATIC_BITS, _MOVING_BITS = (1, 2), (2, 1)
"""(contype, conaffinity) of static and moving geoms in the scratch model: a pair collides when
``contype1 & conaffinity2 or contype2 & conaffinity1``, so only moving-static pairs do."""


@dataclass(frozen=True)
class Allowance:
    """What a move may touch.  ``pairs``: (moving geom, static geom) pairs that may touch (those in
    contact where the move starts).  ``tool_may_touch``: owner ids (object ids, :data:`TABLE` for
    the table) that the cup and the carried object, but no arm link, may touch."""

    pairs: frozenset[tuple[int, int]] = frozenset()
    tool_may_touch: frozenset[int] = frozenset()
    tool_near: bool = False
    """The cup and the carried object may come within ``clearance`` of anything (touching no more
    than :data:`TOUCH_TOL` deep): a guarded descent, whose end is a precise placement next to
    its neighbours."""

    def __or__(self, other: "Allowance") -> "Allowance":
        return Allowance(self.pairs | other.pairs, self.tool_may_touch | other.tool_may_touch,
                         self.tool_near or other.tool_near)


@dataclass(frozen=True)
class Collision:
    """A contact that was not meant to happen: which part (a link, the cup, the carried object)
    touched what (an object's name or ``the table``), and the distance (m; negative: penetration)."""

    part: str
    other: str
    dist: float
    moving_geom: int
    static_geom: int

    def __str__(self) -> str:
        depth = f"{-self.dist * 100:.1f} cm deep" if self.dist < 0 else f"{self.dist * 1000:.0f} mm close"
        return f"{self.part} would touch {self.other} ({depth})"


class CollisionChecker:
    """Checks arm configurations of one world against its objects as they are now (see the module
    docstring).  Call :meth:`sync` after the world changed (an object moved, a grip or release)."""

    def __init__(self, world: World, clearance: float = CLEARANCE) -> None:
        self.world = world
        self.clearance = clearance
        m = world.model
        self.model = _copy_model(m)
        self.data = mujoco.MjData(self.model)
        # The shoulder link only turns about its own vertical axis next to the base: it never
        # moves towards anything, and it always sits within the clearance of the table.
        robot_bodies = {m.body(n).id for n in (*ARM_BODIES, SUCTION_BODY) if n != "shoulder_link"}
        collides = (m.geom_contype != 0) | (m.geom_conaffinity != 0)
        self._robot_geoms = np.flatnonzero(collides & np.isin(m.geom_bodyid, list(robot_bodies)))
        self._object_geoms = np.flatnonzero(collides & (world.geom_obj > 0))
        self._table_geoms = np.flatnonzero(collides & (world.geom_obj == 0)
                                           & ~np.isin(np.arange(m.ngeom), self._robot_geoms))
        self._suction_body = m.body(SUCTION_BODY).id
        self._qadr = world.arm_qpos
        self._joints = np.array([m.joint(j).id for j in ARM_JOINTS])
        joint_body = {int(m.jnt_bodyid[j]): k for k, j in enumerate(self._joints)}
        self._last_joint: dict[int, int] = {}
        for b in range(m.nbody):  # the last arm joint before each body (bodies after the arm: the last)
            a = b
            while a and a not in joint_body:
                a = int(m.body_parentid[a])
            self._last_joint[b] = joint_body.get(a, len(self._joints) - 1)
        self._robot_reach = np.ones(len(self._joints))
        self._reach = self._robot_reach
        self._held: int | None = None
        self._held_geoms = np.empty(0, dtype=int)
        self._held_qadr = -1
        self._held_rel_pos = np.zeros(3)
        self._held_rel_mat = np.eye(3)
        self._quat = np.zeros(4)
        self._names = self._part_names()
        self._robot_reach = self._joint_reach(world.data, self._robot_geoms)  # the same in every configuration
        self.checks = 0
        """Configurations checked so far (a deterministic measure of planning effort)."""
        self.sync()

    def _part_names(self) -> dict[int, str]:
        m, w = self.model, self.world
        names: dict[int, str] = {}
        for g in self._robot_geoms:
            body = m.body(int(m.geom_bodyid[g])).name
            names[int(g)] = "the suction cup" if int(g) == w.cup_geom else f"the arm's {body}"
        for g in self._object_geoms:
            names[int(g)] = f"the {w.objects_by_id[int(w.geom_obj[g])].name}"
        for g in self._table_geoms:
            names[int(g)] = "the table"
        return names

    # ------------------------------------------------------------------ state
    def sync(self) -> None:
        """Copy the world's object poses and grip into the scratch model and data."""
        w, m, d = self.world, self.model, self.data
        d.qpos[:] = w.data.qpos
        mujoco.mj_kinematics(m, d)
        held = w.suction.held
        self._held = held
        self._held_geoms = self._object_geoms[w.geom_obj[self._object_geoms] == held] if held is not None \
            else np.empty(0, dtype=int)
        moving = np.concatenate([self._robot_geoms, self._held_geoms])
        m.geom_contype[:], m.geom_conaffinity[:] = 0, 0
        m.geom_margin[:] = 0.0
        for geoms, (ctype, caff) in ((np.concatenate([self._object_geoms, self._table_geoms]), _STATIC_BITS),
                                     (moving, _MOVING_BITS)):
            m.geom_contype[geoms], m.geom_conaffinity[geoms] = ctype, caff
        m.geom_margin[moving] = max(LOOKAHEAD, self.clearance)
        self._moving = np.zeros(m.ngeom, dtype=bool)
        self._moving[moving] = True
        self._moving_list: list[bool] = self._moving.tolist()
        self._tool = np.zeros(m.ngeom, dtype=bool)
        self._tool[[w.cup_geom, *self._held_geoms.tolist()]] = True
        self._reach = self._robot_reach if held is None else \
            np.maximum(self._robot_reach, self._joint_reach(w.data, self._held_geoms))
        for b in range(m.nbody):
            m.body_contype[b] = int(np.bitwise_or.reduce(m.geom_contype[m.geom_bodyid == b], initial=0))
            m.body_conaffinity[b] = int(np.bitwise_or.reduce(m.geom_conaffinity[m.geom_bodyid == b], initial=0))
        # The carried body's pose in the suction body's frame (live data: the weld holds it).
        self._held_qadr = w.free_qpos[held] if held is not None else -1
        if held is not None:
            sp, sr = w.data.xpos[self._suction_body], w.data.xmat[self._suction_body].reshape(3, 3)
            b = w.body_of[held]
            self._held_rel_pos = sr.T @ (w.data.xpos[b] - sp)
            self._held_rel_mat = sr.T @ w.data.xmat[b].reshape(3, 3)

    def _joint_reach(self, data: mujoco.MjData, moving: np.ndarray) -> np.ndarray:
        """Per arm joint, a bound (m) on how far from its anchor any point of a moving geom beyond
        it can be, in any configuration: the chain of anchor-to-anchor distances (fixed by the
        rigid links) plus the geom's centre from the last anchor before it and its bounding
        radius.  Turning joint i by dq moves no such point more than ``reach[i] * |dq|``."""
        m = self.model
        anchors = data.xanchor[self._joints]
        links = np.linalg.norm(np.diff(anchors, axis=0), axis=1)  # anchor i to anchor i + 1
        reach = np.zeros(len(self._joints))
        for g in moving.tolist():
            k = self._last_joint[int(m.geom_bodyid[g])]
            extent = float(np.linalg.norm(data.geom_xpos[g] - anchors[k]) + m.geom_rbound[g])
            for i in range(k + 1):
                reach[i] = max(reach[i], float(links[i:k].sum()) + extent)
        return reach

    @property
    def held(self) -> int | None:
        """The object carried at the last :meth:`sync` (it moves with the cup)."""
        return self._held

    def _pose(self, q: np.ndarray) -> None:
        """Forward kinematics of arm joints ``q`` with the carried object following the cup (its
        free joint set from the suction body's pose, then the kinematics run again, so the
        collision broadphase sees the carried body where it is)."""
        m, d = self.model, self.data
        d.qpos[self._qadr] = q
        mujoco.mj_kinematics(m, d)
        a = self._held_qadr
        if a >= 0:
            sp, sr = d.xpos[self._suction_body], d.xmat[self._suction_body].reshape(3, 3)
            d.qpos[a:a + 3] = sp + sr @ self._held_rel_pos
            mujoco.mju_mat2Quat(self._quat, (sr @ self._held_rel_mat).ravel())
            d.qpos[a + 3:a + 7] = self._quat
            mujoco.mj_kinematics(m, d)

    def contacts(self, q: np.ndarray) -> list[tuple[int, int, float]]:
        """Every (moving geom, static geom, distance) pair within ``clearance`` at joints ``q``."""
        m, d = self.model, self.data
        self._pose(q)
        mujoco.mj_collision(m, d)
        self.checks += 1
        n = d.ncon
        if n == 0:
            return []
        moving = self._moving_list
        out = []
        for (g1, g2), dist in zip(d.contact.geom[:n].tolist(), d.contact.dist[:n].tolist()):
            out.append((g2, g1, dist) if moving[g2] else (g1, g2, dist))
        return out

    def owner(self, static_geom: int) -> int:
        """The owner id of a static geom: its object id, or :data:`TABLE`."""
        return int(self.world.geom_obj[static_geom])

    # ------------------------------------------------------------------ queries
    def _check(self, q: np.ndarray, allow: Allowance) -> tuple[Collision | None, float]:
        """(The closest contact at joints ``q`` within ``clearance`` that ``allow`` does not cover,
        or None; the distance (m) to the nearest thing ``allow`` does not cover, at most
        :data:`LOOKAHEAD`)."""
        worst: Collision | None = None
        free = LOOKAHEAD
        for g1, g2, dist in self.contacts(q):
            if (g1, g2) in allow.pairs and dist < self.clearance:
                continue
            if self._tool[g1] and (self.owner(g2) in allow.tool_may_touch
                                   or (allow.tool_near and dist > -TOUCH_TOL)):
                continue
            free = min(free, dist)
            if dist < self.clearance and (worst is None or dist < worst.dist):
                worst = Collision(self._part(g1), self._names.get(g2, "the table"), dist, g1, g2)
        return worst, free

    def _part(self, g: int) -> str:
        return f"the carried {self._names[g][4:]}" if self._tool[g] and g != self.world.cup_geom else self._names[g]

    def collision(self, q: np.ndarray, allow: Allowance = Allowance()) -> Collision | None:
        """The closest contact at joints ``q`` that ``allow`` does not cover, or None if clear."""
        return self._check(q, allow)[0]

    def tool_inside(self, q: np.ndarray, depth: float) -> Collision | None:
        """The deepest penetration of the cup or the carried object into anything at joints ``q``
        when it is deeper than ``depth`` (m), else None: a target pose inside an object."""
        worst: Collision | None = None
        for g1, g2, dist in self.contacts(q):
            if self._tool[g1] and dist < -depth and (worst is None or dist < worst.dist):
                worst = Collision(self._part(g1), self._names.get(g2, "the table"), dist, g1, g2)
        return worst

    def touching(self, q: np.ndarray) -> frozenset[tuple[int, int]]:
        """The (moving, static) geom pairs within ``clearance`` at joints ``q`` (to allow at a start)."""
        return frozenset((g1, g2) for g1, g2, d in self.contacts(q) if d < self.clearance)

    def tool_owners(self, q: np.ndarray) -> frozenset[int]:
        """Owner ids the cup or the carried object is within ``clearance`` of at joints ``q``."""
        return frozenset(self.owner(g2) for g1, g2, d in self.contacts(q) if self._tool[g1] and d < self.clearance)

    def path_collision(self, qs: np.ndarray, allow: Allowance = Allowance()) -> tuple[int, Collision] | None:
        """The first collision along the joint path through the rows of ``qs`` (straight in joint
        space between rows): (row index before it, collision), or None if the whole path is clear.

        Checked by conservative advancement: where the nearest thing not allowed is ``d`` away, no
        point of the arm, the cup or the carried object can come within the clearance of it before
        the joints have moved ``d - clearance`` metres of reach-weighted change
        (:meth:`_joint_reach`), so the next check is there, and never nearer than
        :data:`CHECK_STEP` of the largest joint's change: checks at most that far apart near
        obstacles, far fewer in free space."""
        qs = np.asarray(qs, float)
        if len(qs) == 0:
            return None
        steps = np.abs(np.diff(qs, axis=0))
        metres = np.concatenate([[0.0], np.cumsum(steps @ self._reach)]).tolist()  # bound on any point's travel
        joint = np.concatenate([[0.0], np.cumsum(steps.max(axis=1, initial=0.0))]).tolist()
        last = len(qs) - 1
        u = 0.0
        while True:
            i = min(int(u), last - 1) if last else 0
            q = qs[i] + (u - i) * (qs[i + 1] - qs[i]) if last else qs[0]
            hit, free = self._check(q, allow)
            if hit is not None:
                return i, hit
            if u >= last:
                return None
            f = u - i
            u_far = _advance(metres, i, metres[i] + f * (metres[i + 1] - metres[i]) + max(free - self.clearance, 0.0))
            u_near = _advance(joint, i, joint[i] + f * (joint[i + 1] - joint[i]) + CHECK_STEP)
            u = min(float(last), max(u_far, u_near, u + 1e-9))


def _advance(cum: list[float], i: int, value: float) -> float:
    """The (fractional) row at which the non-decreasing ``cum`` reaches ``value``, from row ``i`` on."""
    last = len(cum) - 1
    j = bisect.bisect_left(cum, value, i + 1)
    if j > last:
        return float(last)
    lo, hi = cum[j - 1], cum[j]
    return float(j) if hi <= lo else (j - 1) + (value - lo) / (hi - lo)


def _copy_model(model: mujoco.MjModel) -> mujoco.MjModel:
    """A private copy of ``model`` (its contact bits and margins are changed for checking)."""
    import copy

    return copy.deepcopy(model)
