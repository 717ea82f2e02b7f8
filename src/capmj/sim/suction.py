"""Suction as weld equalities, Ravens style: grip on contact, movable objects only.

Each movable object has its own inactive weld to the suction body.  On :meth:`Suction.grip` the
current relative pose is written into ``model.eq_data`` *before* activation — otherwise MuJoCo
enforces the relative pose of ``qpos0`` and the object jumps (measured: 1.22 m).  Fixed objects
have no weld, so they can never be picked.
"""

from __future__ import annotations

from typing import Mapping

import mujoco
import numpy as np

CUP = -1
"""Owner id :func:`contact_owners` reports for the suction cup."""


def contact_owners(data: mujoco.MjData, geom_obj: np.ndarray, cup_geom: int, obj_id: int) -> set[int]:
    """Ids of what touches object ``obj_id``: other object ids, 0 for table/floor/robot, ``CUP`` for the cup."""
    geoms = data.contact.geom[: data.ncon]
    if not len(geoms):
        return set()
    owners = geom_obj[geoms]
    out: set[int] = set()
    for col, other in ((0, 1), (1, 0)):
        rows = owners[:, col] == obj_id
        if rows.any():
            out.update(int(geom_obj[g]) if g != cup_geom else CUP for g in geoms[rows, other])
    return out


class Suction:
    """The suction cup of one world.  It holds no state of its own: what is held is read from the
    active welds, so restoring a physics snapshot restores the grip too (call :meth:`sync` after
    one: the held object's collision filter follows the weld).

    While an object is held, it and the cup do not collide: the weld already fixes their relative
    pose, and the cup–object contact only added constraint rows (a cylinder–box pair, ~4 contact
    points) that made each step of a carry cost 2.5 times a step with nothing held (measured:
    33 against 13 µs).  Both keep colliding with everything else (table, objects, arm), so a
    carried object still lands on what is under it and the cup can still strike another object.

    ``geom_obj`` maps every geom to its object id (0 for robot, table, floor), ``body_of`` and
    ``weld_of`` map movable object ids to their body and weld equality.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, *, suction_body: int, cup_geom: int,
                 geom_obj: np.ndarray, body_of: Mapping[int, int], weld_of: Mapping[int, int]) -> None:
        self.model, self.data = model, data
        self._suction_body, self._cup = suction_body, cup_geom
        self._geom_obj, self._body_of, self._weld_of = geom_obj, body_of, weld_of
        self._movable = frozenset(weld_of)
        self._affinity = model.geom_conaffinity.copy()  # as compiled: restored on release
        self._body_affinity = model.body_conaffinity.copy()
        self._cup_body = int(model.geom_bodyid[cup_geom])
        self._geoms_of = {i: np.flatnonzero(geom_obj == i) for i in weld_of}
        self._geom_obj_list: list[int] = [int(o) for o in geom_obj]
        self._welds = list(weld_of.items())

    @property
    def held(self) -> int | None:
        """The object whose weld is active, if any."""
        active = self.data.eq_active
        for i, e in self._welds:
            if active[e]:
                return i
        return None

    def touching(self) -> int | None:
        """The movable object the cup touches, if any (lowest obj_id when several).

        Called every physics step during descents, so it scans the contact list once.
        """
        d = self.data
        if d.ncon == 0:
            return None
        geoms = d.contact.geom[: d.ncon]
        cup = self._cup
        rows = (geoms[:, 0] == cup) | (geoms[:, 1] == cup)
        if not rows.any():
            return None
        pairs = geoms[rows]
        owners = self._geom_obj[np.where(pairs[:, 0] == cup, pairs[:, 1], pairs[:, 0])]
        movable = [int(o) for o in owners if o in self._movable]
        return min(movable) if movable else None

    def grip(self) -> int | None:
        """Activate the weld of the touched movable object; returns its id or None."""
        held = self.held
        if held is not None:
            return held
        obj = self.touching()
        if obj is None:
            return None
        m, d = self.model, self.data
        eq = self._weld_of[obj]
        b1, b2 = self._suction_body, self._body_of[obj]
        r1 = d.xmat[b1].reshape(3, 3)
        q1inv = np.zeros(4)
        mujoco.mju_negQuat(q1inv, d.xquat[b1])
        relq = np.zeros(4)
        mujoco.mju_mulQuat(relq, q1inv, d.xquat[b2])
        m.eq_data[eq, 0:3] = 0.0
        m.eq_data[eq, 3:6] = r1.T @ (d.xpos[b2] - d.xpos[b1])
        m.eq_data[eq, 6:10] = relq
        d.eq_active[eq] = 1
        self.sync()
        return obj

    def release(self) -> int | None:
        """Deactivate the weld; returns the id that was held."""
        obj = self.held
        if obj is not None:
            self.data.eq_active[self._weld_of[obj]] = 0
            self.sync()
        return obj

    def sync(self) -> None:
        """Set the collision filter from the active weld: the held object and the cup lose their
        affinity bits (so neither accepts the other's type) while everything else keeps its own."""
        m, held = self.model, self.held
        m.geom_conaffinity[:] = self._affinity
        m.body_conaffinity[:] = self._body_affinity
        if held is not None:
            for g in (self._cup, *self._geoms_of[held]):
                m.geom_conaffinity[g] = 0
            for b in (self._cup_body, self._body_of[held]):
                m.body_conaffinity[b] = int(np.bitwise_or.reduce(m.geom_conaffinity[m.geom_bodyid == b]))

    def held_touches_other(self) -> bool:
        """True when the held object touches anything but the cup (placing is detected this way).

        Called every physics step while a carried object is lowered, so it avoids building sets.
        """
        d = self.data
        n = d.ncon
        if n == 0:
            return False
        held = self.held
        if held is None:
            return False
        # a handful of contacts: plain Python over them costs less than numpy's per-call overhead
        owner, cup = self._geom_obj_list, self._cup
        for g1, g2 in d.contact.geom[:n].tolist():
            if (owner[g1] == held and g2 != cup) or (owner[g2] == held and g1 != cup):
                return True
        return False
