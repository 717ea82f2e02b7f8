"""CapRavens' names in the planner API: functions its prompt code calls that capmj's own prompts
do not use.

CapRavens' few-shot examples call ``denormalize_xy``, ``denormalize_bbox``, ``is_obj_visible``,
``bbox_contains_pt`` and ``reset``; capmj's prompts have their own names for most of that
(``denormalize``, ``is_target_occupied``) and leave resetting to the benchmark's loop.  The methods of :class:`CapRavensFunctions` make the original's code run
as written (``benchmarks/capravens_examples.py`` counts how much does); :class:`~capmj.agents.api.plan_functions.
PlanFunctions` inherits them, so they are planner API functions like any other (named in
``API_FUNCTIONS``, logged; all read-only but ``reset``, which only plan code gets).  They are not listed in ``prompts/planner.py``: small
models read that prompt, and these names only serve code ported from CapRavens (the porting table
of ``docs/llm.md`` lists them).  Names are resolved and geometry computed by the
:class:`~capmj.agents.api.planner_api.PlannerAPI` and :mod:`capmj.agents.api.footprints`, as for every function.
"""

from __future__ import annotations

import numpy as np

from capmj.agents.api.interface import PlannerInterface
from capmj.agents.api.values import denormalize_uv, is_vector, summary
from capmj.errors import PortingDifference, UnknownObjectError

INSIDE_TOL = 1e-9
"""A centre this close (m) to a footprint counts as inside it: the edge belongs to the footprint."""


class CapRavensFunctions:
    """The CapRavens-named planner API functions over a :class:`~capmj.agents.api.planner_api.PlannerAPI`."""

    _api: PlannerInterface

    def denormalize_xy(self, pos: list[float], size: list[float] | None = None) -> np.ndarray:
        """CapRavens' name for ``denormalize``: normalised [u, v] → world [x, y] (a numpy array,
        as there).  With ``size`` = (sx, sy) the result is an offset inside a box of that size
        centred on the origin instead: [v sx − sx/2, u sy − sy/2] (the original's formula)."""
        arr = np.asarray(pos, float)
        if arr.ndim != 1 or len(arr) != 2:
            raise ValueError(f"denormalize_xy expects [u, v], got {summary(pos, 80)}")
        if size is None:
            return np.array(denormalize_uv(arr[0], arr[1]))
        sx, sy = (float(v) for v in size[:2])
        return np.array([arr[1] * sx - sx / 2, arr[0] * sy - sy / 2])

    def denormalize_bbox(self, bbox: tuple[float, float, float, float]) -> list[float]:
        """A normalised area (umin, vmin, umax, vmax) → the world area (xmin, ymin, xmax, ymax), as
        ``get_random_free_pos(area=...)`` takes it (CapRavens' ``denormalize_bbox``)."""
        if not is_vector(bbox, (4,)):
            raise ValueError(f"denormalize_bbox expects (umin, vmin, umax, vmax), got {summary(bbox, 80)}")
        umin, vmin, umax, vmax = (float(v) for v in bbox)
        x0, y0 = denormalize_uv(umin, vmax)
        x1, y1 = denormalize_uv(umax, vmin)
        return [x0, y0, x1, y1]

    def is_obj_visible(self, obj: str | int) -> bool:
        """Whether the scene has an object of that name (or obj_id): True exactly when the other
        functions accept the name, near-miss names included (CapRavens' ``is_obj_visible``)."""
        try:
            self._api.resolve(obj)
        except (UnknownObjectError, PortingDifference):
            return False
        return True

    def bbox_contains_pt(self, container_name: str | int, obj_name: str | int) -> bool:
        """Whether ``obj_name``'s centre lies inside ``container_name``'s footprint, seen from
        above: a zone's square turned by its yaw (capmj's one rule for "in the zone", the one
        the tasks judge by), a bowl's disc, a block's turned square.  Height is not checked, so a
        block on a stack in a zone is in it.  (The name says bounding box, but a turned zone's
        world box is larger than the zone, and capmj has one rule for "in": the footprint.)"""
        api = self._api
        container, obj = api.resolve(container_name), api.resolve(obj_name)
        if container.obj_id == obj.obj_id:
            raise ValueError(f"bbox_contains_pt needs two different objects, got {obj.name!r} twice")
        xy = api.position(obj.obj_id)[:2]
        return api.footprints.distance(xy, container) <= INSIDE_TOL

    def reset(self) -> None:
        """CapRavens' ``reset()``: the scene back to the episode's initial state, so a plan whose
        own check failed can try again from the start (its examples do: check, ``reset()``,
        retry).  The original re-ran ``env.reset()`` with the episode's seed, i.e. rebuilt the
        same initial scene; capmj restores the settled initial state the episode began from,
        exactly as the benchmark's re-plan reset does (spec: "a reset of the scene to the
        episode's initial state"): a state physics produced, with no object put where no robot
        could have put it.  It does not open a new attempt: the pick-and-places and simulation
        steps spent before it still count against the attempt's budgets.  Recorded in the call
        log and as ``planner/reset`` in the episode's log."""
        api = self._api
        before = api.world.time
        api.reset_scene()
        api.ctx.recorder.text("planner/reset", f"scene reset to the episode's initial state at t={before:.2f}s "
                               "(budgets keep counting)", api.world.time)
