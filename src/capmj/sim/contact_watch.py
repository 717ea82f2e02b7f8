"""New contacts of the robot during a move: what a robot driver's contact monitor reports.

:class:`ContactWatch` is made when a move starts and asked after every physics step whether an arm
link, the suction cup or the carried object touches the table or an object in a way it did not when
the move started (or in one of the ``allowed`` ways, e.g. what the last move ended touching).  The
low-level planner API (:mod:`capmj.agents.api.low_level_robot`) stops a move on it: a guarded move
ends on its tool's contact, any other new contact is a collision.  Contacts are read from MuJoCo's
contact list, so this lives with the world, below the agents.
"""

from __future__ import annotations

from typing import Iterable

from capmj.sim.world import World

TABLE, CUP, LINK = -2, -1, 0
"""Owner codes of geoms that are no object: the table and floor, the suction cup, an arm link
(objects are their obj_id, >= 1)."""


def owners(world: World) -> list[int]:
    """Each geom's owner code: its obj_id, or :data:`TABLE`, :data:`CUP`, :data:`LINK`."""
    m = world.model
    out = []
    for g in range(m.ngeom):
        obj = int(world.geom_obj[g])
        if obj > 0:
            out.append(obj)
        elif g == world.cup_geom:
            out.append(CUP)
        elif int(m.geom_bodyid[g]) == 0:
            out.append(TABLE)
        else:
            out.append(LINK)
    return out


class ContactWatch:
    """New contacts of the robot and its load during one move (see the module docstring)."""

    def __init__(self, world: World, allowed: Iterable[tuple[int, int]] = ()) -> None:
        self._world = world
        self._owner = owners(world)
        self._held = world.suction.held
        self._start = self._pairs() | set(allowed)
        """What may touch: the contacts now, and ``allowed`` (those the last move ended with, which
        may part and touch again as this one leaves them; the object the cup has just let go)."""
        self.hit: tuple[int, int] | None = None
        """The first new contact, as (robot side: ``CUP``, ``LINK`` or the held obj_id; the other
        side's owner code)."""

    def _relevant(self, g1: int, g2: int) -> tuple[int, int] | None:
        o1, o2, held = self._owner[g1], self._owner[g2], self._held
        for a, b in ((o1, o2), (o2, o1)):
            if a in (CUP, LINK) and b not in (CUP, LINK):
                if held is not None and a == CUP and b == held:
                    continue
                return a, b
            if held is not None and a == held and b not in (CUP, held):
                return a, b
        return None

    def _pairs(self) -> set[tuple[int, int]]:
        d = self._world.data
        out = set()
        for g1, g2 in d.contact.geom[: d.ncon].tolist():
            pair = self._relevant(g1, g2)
            if pair is not None:
                out.add(pair)
        return out

    def new_contact(self) -> bool:
        """Whether a contact exists now that did not at the start (kept in :attr:`hit`); called
        every physics step of a move."""
        d = self._world.data
        n = d.ncon
        if n == 0:
            return False
        for g1, g2 in d.contact.geom[:n].tolist():
            pair = self._relevant(g1, g2)
            if pair is not None and pair not in self._start:
                self.hit = pair
                return True
        return False

    def ending(self) -> set[tuple[int, int]]:
        """The contacts at the end of the move (its stopping contact included), for the next move."""
        return self._pairs() | ({self.hit} if self.hit is not None else set())

    def tool_contact(self) -> bool:
        """Whether :attr:`hit` is the tool's own contact: the cup's with nothing held, the carried
        object's when one is held."""
        if self.hit is None:
            return False
        return self.hit[0] == (CUP if self._held is None else self._held)




__all__ = ["CUP", "LINK", "TABLE", "ContactWatch", "owners"]
