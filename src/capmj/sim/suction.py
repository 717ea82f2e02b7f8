"""Suction as weld equalities, Ravens style: grip on contact, movable objects only.

Each movable object has its own inactive weld to the suction body.  On :meth:`Suction.grip` the
current relative pose is written into ``model.eq_data`` *before* activation — otherwise MuJoCo
enforces the relative pose of ``qpos0`` and the object jumps (measured: 1.22 m).  Fixed objects
have no weld, so they can never be picked.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

if TYPE_CHECKING:
    from capmj.sim.world import World


class Suction:
    def __init__(self, world: "World") -> None:
        self.world = world
        self.held: int | None = None
        self._suction_body = world.model.body("suction").id
        self._movable = frozenset(world.movable_ids)

    def sync(self) -> None:
        """Re-derive ``held`` from the active welds (after a state restore)."""
        d = self.world.data
        self.held = next((i for i, e in self.world.weld_of.items() if d.eq_active[e]), None)

    def touching(self) -> int | None:
        """The movable object the cup touches, if any (lowest obj_id when several).

        Called every physics step during descents, so it scans the contact list once.
        """
        w = self.world
        d = w.data
        if d.ncon == 0:
            return None
        geoms = d.contact.geom[: d.ncon]
        cup = w.cup_geom
        rows = (geoms[:, 0] == cup) | (geoms[:, 1] == cup)
        if not rows.any():
            return None
        pairs = geoms[rows]
        owners = w.geom_obj[np.where(pairs[:, 0] == cup, pairs[:, 1], pairs[:, 0])]
        movable = [int(o) for o in owners if o in self._movable]
        return min(movable) if movable else None

    def grip(self) -> int | None:
        """Activate the weld of the touched movable object; returns its id or None."""
        if self.held is not None:
            return self.held
        obj = self.touching()
        if obj is None:
            return None
        w = self.world
        m, d = w.model, w.data
        eq = w.weld_of[obj]
        b1, b2 = self._suction_body, w.body_of[obj]
        r1 = d.xmat[b1].reshape(3, 3)
        q1inv = np.zeros(4)
        mujoco.mju_negQuat(q1inv, d.xquat[b1])
        relq = np.zeros(4)
        mujoco.mju_mulQuat(relq, q1inv, d.xquat[b2])
        m.eq_data[eq, 0:3] = 0.0
        m.eq_data[eq, 3:6] = r1.T @ (d.xpos[b2] - d.xpos[b1])
        m.eq_data[eq, 6:10] = relq
        d.eq_active[eq] = 1
        self.held = obj
        return obj

    def release(self) -> int | None:
        """Deactivate the weld; returns the id that was held."""
        obj = self.held
        if obj is not None:
            self.world.data.eq_active[self.world.weld_of[obj]] = 0
        self.held = None
        return obj

    def held_touches_other(self) -> bool:
        """True when the held object touches anything but the cup (placing is detected this way)."""
        if self.held is None:
            return False
        return bool(self.world.contacts_of(self.held) - {-1})
