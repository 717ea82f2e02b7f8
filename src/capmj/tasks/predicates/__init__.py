"""Shared geometric predicates for success checks: pure functions over a :class:`SceneState`.

Every predicate judges one settled snapshot (never a history) and documents its tolerance.  The
tolerances are the originals' (Ravens/CapRavens): plane position 0.01 m (0.05 m for bowls),
rotation 15 degrees, vertical 0.015 m.  Positions are object *centres* in metres, world frame
(robot base at the origin, table top at z = 0); quaternions in states are (w, x, y, z).

Area words follow the front-camera image: "top" = x in [0.25, 0.5], "bottom" = x in [0.5, 0.75],
"left" = y < 0, "right" = y > 0, and combinations such as "top left".

One module per concept: :mod:`~.tolerances`, :mod:`~.areas` (named areas, "did not move"),
:mod:`~.containment` (zones, bowls), :mod:`~.stacks`, :mod:`~.layouts` (grids, layers,
footprints that touch or support, rows), :mod:`~.circles`, :mod:`~.fixtures` (L-fixture slots),
:mod:`~.counts` (goal arithmetic), :mod:`~.reward` (the Ravens matching reward) and
:mod:`~.labels`.  Tasks import them from here: ``__all__`` is the documented surface, the names
LLM-written tasks may use (:mod:`capmj.confine.allowlist`), in the order the generator's prompt
lists them.
"""

from __future__ import annotations

from capmj.tasks.predicates.areas import (
    AREA_NAMES,
    QUADRANTS,
    WORKSPACE_X,
    WORKSPACE_Y,
    WORKSPACE_Z,
    area_bounds,
    in_area,
    moved_less_than,
)
from capmj.tasks.predicates.circles import CENTRE_TOL, CIRCLE_TOL, alternates, angular_order, circle_of, concentric, fit_circle
from capmj.tasks.predicates.containment import (
    bowl_floor_z,
    bowl_rim_z,
    in_bowl,
    in_square,
    in_zone,
    objects_in_zone,
    zone_half_size,
    zone_local_xy,
    zone_outside_distance,
)
from capmj.tasks.predicates.counts import group_sizes, largest_odd_at_most, zone_color_counts
from capmj.tasks.predicates.fixtures import (
    FIXTURE_RADIUS,
    FIXTURE_SLOT,
    FIXTURE_SLOTS_LOCAL,
    SLOT_TOL,
    fixture_slots,
    slot_occupants,
)
from capmj.tasks.predicates.labels import positions, short_label
from capmj.tasks.predicates.layouts import (
    ROW_LINE_TOL,
    ROW_MID_TOL,
    ROW_PITCH_TOL,
    TOUCH_GAP,
    RowReport,
    footprint,
    is_grid,
    is_layer,
    row_on_line,
    supporters,
    touching_pairs,
)
from capmj.tasks.predicates.reward import max_matching, ravens_reward
from capmj.tasks.predicates.stacks import (
    ZoneStack,
    build_tower,
    find_stack_order,
    is_stack,
    resting_on,
    resting_on_table,
    toppled,
    zone_stacks,
)
from capmj.tasks.predicates.tolerances import BOWL_TOL, MOVE_TOL, PLANE_TOL, STACK_AXIS_TOL, TILT_TOL, YAW_TOL, Z_TOL

__all__ = [
    "AREA_NAMES", "BOWL_TOL", "MOVE_TOL", "PLANE_TOL", "QUADRANTS", "STACK_AXIS_TOL", "TILT_TOL", "YAW_TOL",
    "Z_TOL", "WORKSPACE_X", "WORKSPACE_Y", "WORKSPACE_Z",
    "area_bounds", "bowl_floor_z", "bowl_rim_z", "build_tower", "find_stack_order", "fit_circle", "in_area",
    "in_bowl", "in_square", "in_zone", "is_grid", "is_stack", "max_matching", "moved_less_than", "objects_in_zone",
    "positions", "ravens_reward", "resting_on", "resting_on_table", "short_label", "toppled", "zone_half_size",
    "zone_local_xy", "zone_outside_distance",
    # the checks of the generated tasks 6–10
    "FIXTURE_RADIUS", "FIXTURE_SLOT", "FIXTURE_SLOTS_LOCAL", "ROW_LINE_TOL", "ROW_MID_TOL", "ROW_PITCH_TOL",
    "RowReport", "SLOT_TOL", "ZoneStack", "fixture_slots", "group_sizes", "largest_odd_at_most", "row_on_line",
    "slot_occupants", "zone_color_counts", "zone_stacks",
    # the layouts of the generated tasks 1–5
    "CENTRE_TOL", "CIRCLE_TOL", "TOUCH_GAP", "alternates", "angular_order", "circle_of", "concentric", "footprint",
    "is_layer", "supporters", "touching_pairs",
]
"""In the order the generator's prompt documents them (kept from the single module, so the prompt
and its cached completions do not change)."""
