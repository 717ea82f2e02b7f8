"""Containment: whether an object is in a zone (the one centre rule of every task) or in a bowl.

A zone is a flat square (side 0.12 m × scale, turned by its yaw): an object is in it when its xy
centre is (the spec's rule, structures included).  A bowl holds an object whose centre is within
``BOWL_TOL`` of the bowl's centre in xy and below its rim.
"""

from __future__ import annotations

import math
from typing import Iterable

import numpy as np

from capmj.sim.objects import BOWL_FLOOR, BOWL_HEIGHT, ZONE_SIZE, ObjectSpec
from capmj.sim.pose import Vector, to_frame_2d
from capmj.sim.state import SceneState
from capmj.tasks.predicates.tolerances import BOWL_TOL


# --------------------------------------------------------------------------------------- zones
def zone_local_xy(state: SceneState, zone_id: int, xy: Vector) -> np.ndarray:
    """``xy`` expressed in the zone's frame (origin at its centre, axes along its sides)."""
    return to_frame_2d(xy[:2], state.poses[zone_id].yaw, state.pos(zone_id)[:2])


def zone_half_size(spec: ObjectSpec) -> float:
    """Half the side (m) of a zone's square, scale included."""
    return ZONE_SIZE * spec.scale / 2


def zone_outside_distance(state: SceneState, obj_id: int, zone_id: int) -> float:
    """How far (m) the xy centre of ``obj_id`` lies outside the zone square; 0 when inside."""
    local = np.abs(zone_local_xy(state, zone_id, state.pos(obj_id)))
    excess = np.maximum(local - zone_half_size(state.spec(zone_id)), 0.0)
    return float(np.hypot(*excess))


def in_square(xy: Vector, centre: Vector, yaw: float, half: float) -> bool:
    """Whether the point ``xy`` lies inside the closed square of half side ``half`` (m) centred on
    ``centre`` and turned by ``yaw`` (rad): the geometry of :func:`in_zone`, for callers that have
    poses but no :class:`SceneState` (the text reporter's ``in_zone``)."""
    local = np.abs(to_frame_2d(np.asarray(xy, float)[:2], yaw, np.asarray(centre, float)[:2]))
    return bool(local[0] <= half + 1e-9 and local[1] <= half + 1e-9)


def in_zone(state: SceneState, obj_id: int, zone_id: int) -> bool:
    """Whether the xy centre of ``obj_id`` lies inside the zone square (side 0.12 m × scale,
    honouring the zone's yaw).  This is the one meaning of "in the zone" in every task, structures
    included (the spec's rule; docs/task_plugins.md, "In the zone"): a block whose corner overhangs
    the zone is in it when its centre is.  Tolerance: none (a centre on the edge counts as inside);
    height is not checked, so a block on top of a stack in the zone is in the zone."""
    return in_square(state.pos(obj_id), state.pos(zone_id), state.poses[zone_id].yaw, zone_half_size(state.spec(zone_id)))


def objects_in_zone(state: SceneState, zone_id: int, kinds: Iterable[str] = ("block",)) -> list[int]:
    """Ids of the objects of the given kinds whose centre is in the zone (see :func:`in_zone`)."""
    kinds = tuple(kinds)
    return [o.obj_id for o in state.objects
            if o.kind in kinds and o.obj_id != zone_id and in_zone(state, o.obj_id, zone_id)]


# --------------------------------------------------------------------------------------- bowls
def bowl_rim_z(state: SceneState, bowl_id: int) -> float:
    """World z (m) of the top of a bowl's rim."""
    return float(state.pos(bowl_id)[2]) + BOWL_HEIGHT / 2


def bowl_floor_z(state_or_pos: SceneState | Vector, bowl_id: int | None = None) -> float:
    """World z (m) of the top of a bowl's floor (bowl centre z − BOWL_HEIGHT/2 + BOWL_FLOOR)."""
    if isinstance(state_or_pos, SceneState):
        if bowl_id is None:
            raise TypeError("bowl_floor_z(state, bowl_id): the bowl's id is needed with a state")
        z = float(state_or_pos.pos(bowl_id)[2])
    else:
        z = float(state_or_pos[2])
    return z - BOWL_HEIGHT / 2 + BOWL_FLOOR


def in_bowl(state: SceneState, obj_id: int, bowl_id: int) -> bool:
    """Whether ``obj_id`` is in the bowl: centre within 0.05 m (``BOWL_TOL``) of the bowl centre in
    xy and strictly below the rim top (bowl centre z + BOWL_HEIGHT/2)."""
    p, b = state.pos(obj_id), state.pos(bowl_id)
    return bool(math.hypot(p[0] - b[0], p[1] - b[1]) <= BOWL_TOL and p[2] < bowl_rim_z(state, bowl_id))


__all__ = ["bowl_floor_z", "bowl_rim_z", "in_bowl", "in_square", "in_zone", "objects_in_zone", "zone_half_size",
           "zone_local_xy", "zone_outside_distance"]
