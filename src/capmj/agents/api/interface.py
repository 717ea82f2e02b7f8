"""What the planner API functions read and do through the facade: :class:`PlannerInterface`.

The functions plan code calls (:mod:`~capmj.agents.api.plan_functions`,
:mod:`~capmj.agents.api.capravens`) are written against this public interface of
:class:`~capmj.agents.api.planner_api.PlannerAPI` (and of its perceiving subclass,
:class:`~capmj.agents.api.perceived.PerceivedAPI`), never against its private attributes, so the
facade imports the functions and the functions do not import the facade.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from capmj.agents.api.footprints import Footprints
from capmj.agents.base import EpisodeContext
from capmj.sim.objects import ObjectSpec
from capmj.sim.world import World

__all__ = ["PlannerInterface"]


class PlannerInterface(Protocol):
    """Names resolved, positions read, arguments read and actions taken for the API functions."""

    said_chars: int
    """Characters of :attr:`messages` together."""
    messages: list[str]
    """What the plan said through ``say``."""

    @property
    def ctx(self) -> EpisodeContext:
        """The episode context the API acts through (budgets, recorder, pick-and-place)."""

    @property
    def world(self) -> World:
        """The world the API reads (live)."""

    @property
    def footprints(self) -> Footprints:
        """Table geometry (footprints, surfaces, occupancy, free positions), read live."""

    def objects(self) -> tuple[ObjectSpec, ...]:
        """Every object's spec, read live."""

    def object_names(self) -> list[str]:
        """The names of every object."""

    def resolve(self, obj: Any) -> ObjectSpec:
        """The spec of a name (a near miss is resolved and logged) or an int obj_id."""

    def position(self, oid: int) -> np.ndarray:
        """[x, y, z] of an object's centre."""

    def quat_xyzw(self, oid: int) -> list[float]:
        """An object's quaternion (x, y, z, w)."""

    def xy(self, pos: Any) -> np.ndarray:
        """xy of a position, a pose or an object name."""

    def occupied(self, targ: Any, r: float) -> list[str]:
        """Names of the objects occupying a target (``is_target_occupied``)."""

    def free_position(self, targ: Any, area: Any, r: float) -> list[float]:
        """A free position in ``area`` keeping clear of ``targ`` (``get_random_free_pos``)."""

    def put(self, obj: Any, target: Any) -> None:
        """One pick-and-place (``put_first_on_second``)."""

    def reset_scene(self) -> None:
        """The episode's initial scene back, within the attempt (a plan's ``reset()``)."""
