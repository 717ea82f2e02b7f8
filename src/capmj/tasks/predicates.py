"""Shared geometric predicates for success checks: pure functions over a :class:`SceneState`.

Every predicate judges one settled snapshot (never a history) and documents its tolerance.  The
tolerances are the originals' (Ravens/CapRavens): plane position 0.01 m (0.05 m for bowls),
rotation 15 degrees, vertical 0.015 m.  Positions are object *centres* in metres, world frame
(robot base at the origin, table top at z = 0); quaternions in states are (w, x, y, z).

Area words follow the front-camera image: "top" = x in [0.25, 0.5], "bottom" = x in [0.5, 0.75],
"left" = y < 0, "right" = y > 0, and combinations such as "top left".
"""

from __future__ import annotations

import math
from typing import Iterable, Mapping, Sequence

import numpy as np

from capmj.sim import footprint as _footprint
from capmj.sim.bounds import WORKSPACE
from capmj.sim.footprint import TILT_TOL
from capmj.sim.objects import BOWL_FLOOR, BOWL_HEIGHT, ZONE_SIZE, ObjectSpec
from capmj.sim.pose import Vector, from_frame_2d, to_frame_2d
from capmj.sim.state import SceneState

PLANE_TOL = 0.01
"""Plane position tolerance (m) of a pose match."""
BOWL_TOL = 0.05
"""A centre within this xy distance (m) of a bowl centre is "in" the bowl (when below the rim)."""
Z_TOL = 0.015
"""Vertical tolerance (m): resting heights and stack gaps."""
YAW_TOL = math.radians(15.0)
"""Rotation tolerance (rad) of an SE(2) pose match."""
STACK_AXIS_TOL = 0.02
"""Every block of a stack has its xy centre within this distance (m) of the stack axis."""
MOVE_TOL = 0.03
"""An object "did not move" when its centre ends within this distance (m) of its start."""

WORKSPACE_X = (WORKSPACE.xmin, WORKSPACE.xmax)
WORKSPACE_Y = (WORKSPACE.ymin, WORKSPACE.ymax)
WORKSPACE_Z = (WORKSPACE.zmin, WORKSPACE.zmax)
"""The workspace's ranges (m), from :data:`capmj.sim.bounds.WORKSPACE`."""

_SPLIT_X, _SPLIT_Y = WORKSPACE.center
"""The lines that halve the workspace: x = 0.5 (top | bottom) and y = 0 (left | right)."""
_AREA_X = {"top": (WORKSPACE.xmin, _SPLIT_X), "bottom": (_SPLIT_X, WORKSPACE.xmax)}
_AREA_Y = {"left": (WORKSPACE.ymin, _SPLIT_Y), "right": (_SPLIT_Y, WORKSPACE.ymax)}
AREA_NAMES: tuple[str, ...] = (
    "top", "bottom", "left", "right", "top left", "top right", "bottom left", "bottom right",
)
QUADRANTS: tuple[str, ...] = ("top left", "top right", "bottom left", "bottom right")


# --------------------------------------------------------------------------------------- areas
def area_bounds(area: str) -> tuple[float, float, float, float]:
    """``(xmin, xmax, ymin, ymax)`` of a named area ("top", "left", "top left", "right bottom"…).

    Words are case-insensitive and may be joined by spaces, hyphens or underscores; an optional
    trailing "area" is ignored.  Unknown words raise ``ValueError`` naming the valid ones.
    """
    words = area.lower().replace("-", " ").replace("_", " ").split()
    if words and words[-1] == "area":
        words = words[:-1]
    x, y = WORKSPACE_X, WORKSPACE_Y
    seen_x = seen_y = False
    for w in words:
        if w in _AREA_X and not seen_x:
            x, seen_x = _AREA_X[w], True
        elif w in _AREA_Y and not seen_y:
            y, seen_y = _AREA_Y[w], True
        else:
            raise ValueError(f"unknown area {area!r}; valid areas: {', '.join(AREA_NAMES)}")
    if not words:
        raise ValueError(f"empty area name; valid areas: {', '.join(AREA_NAMES)}")
    return (x[0], x[1], y[0], y[1])


def in_area(pos: Vector, area: str | tuple[float, float, float, float]) -> bool:
    """Whether the xy of ``pos`` lies in the area (a name or ``(xmin, xmax, ymin, ymax)``).

    Tolerance: none.  Bounds are inclusive on the workspace edges; the split lines x = 0.5 and
    y = 0 belong to neither side (left is y < 0, right is y > 0, top x < 0.5, bottom x > 0.5), so
    a centre exactly on a split line is in no half.
    """
    b = area_bounds(area) if isinstance(area, str) else area
    x, y = float(pos[0]), float(pos[1])
    return _in_closed_or_split(x, b[0], b[1], _SPLIT_X) and _in_closed_or_split(y, b[2], b[3], _SPLIT_Y)


def _in_closed_or_split(v: float, lo: float, hi: float, split: float) -> bool:
    lo_ok = v > lo if lo == split else v >= lo
    hi_ok = v < hi if hi == split else v <= hi
    return lo_ok and hi_ok


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


# --------------------------------------------------------------------------------------- stacks
def toppled(state: SceneState, obj_id: int, max_tilt: float = TILT_TOL) -> bool:
    """Whether the object is tilted more than 15° (``TILT_TOL``) from resting on any face."""
    return state.poses[obj_id].tilt > max_tilt


def resting_on_table(state: SceneState, obj_id: int, tol: float = Z_TOL) -> bool:
    """Whether the centre height is half the object's height ± 0.015 m (on the table or a zone)."""
    return abs(float(state.pos(obj_id)[2]) - state.spec(obj_id).height / 2) <= tol


def resting_on(state: SceneState, upper: int, lower: int, tol: float = Z_TOL) -> bool:
    """Whether ``upper`` sits on ``lower``: z gap = mean of the two heights ± 0.015 m and xy
    centres within 0.02 m (``STACK_AXIS_TOL``)."""
    pu, pl = state.pos(upper), state.pos(lower)
    gap = (state.spec(upper).height + state.spec(lower).height) / 2
    return bool(abs((pu[2] - pl[2]) - gap) <= tol and math.hypot(pu[0] - pl[0], pu[1] - pl[1]) <= STACK_AXIS_TOL)


def find_stack_order(state: SceneState, ids: Iterable[int]) -> list[int]:
    """``ids`` sorted bottom to top by centre height (ties broken by id)."""
    return sorted(ids, key=lambda i: (float(state.pos(i)[2]), i))


def is_stack(state: SceneState, ids_bottom_to_top: Sequence[int]) -> tuple[bool, str]:
    """Whether the objects form one stack in the given order, with a reason when not.

    Tolerances: every xy centre within 0.02 m of the stack axis (the vertical line through the
    lowest object's centre); the lowest resting on the table or a zone (z = half its height ±
    0.015 m); each next resting on the previous one (z gap = mean of the two heights ± 0.015 m);
    none tilted more than 15°.  A single upright object on the table is a stack of one.
    """
    ids = list(ids_bottom_to_top)
    if not ids:
        return False, "no objects to stack"
    for i in ids:
        if toppled(state, i):
            return False, f"{short_label(state.spec(i))} is tilted {math.degrees(state.poses[i].tilt):.0f}° (max 15°)"
    base = state.pos(ids[0])
    if not resting_on_table(state, ids[0]):
        want = state.spec(ids[0]).height / 2
        return False, (f"bottom {short_label(state.spec(ids[0]))} is not on the table "
                       f"(z = {base[2]:.3f} m, expected {want:.3f} ± {Z_TOL})")
    for lower, upper in zip(ids, ids[1:]):
        pu, pl = state.pos(upper), state.pos(lower)
        off = math.hypot(pu[0] - base[0], pu[1] - base[1])
        if off > STACK_AXIS_TOL:
            return False, (f"{short_label(state.spec(upper))} is {off:.3f} m off the stack axis "
                           f"(max {STACK_AXIS_TOL})")
        gap = (state.spec(upper).height + state.spec(lower).height) / 2
        dz = float(pu[2] - pl[2])
        if abs(dz - gap) > Z_TOL:
            return False, (f"{short_label(state.spec(upper))} is not resting on {short_label(state.spec(lower))} "
                           f"(z gap {dz:.3f} m, expected {gap:.3f} ± {Z_TOL})")
    return True, f"{len(ids)} object(s) stacked"


def build_tower(
    state: SceneState,
    ids: Iterable[int],
    zone_id: int | None = None,
    accept=None,
) -> list[int]:
    """The tallest stack (bottom first) that can be formed from ``ids`` as they lie.

    A tower starts with an upright object resting on the table (inside ``zone_id`` when given) and
    grows by objects resting on the current top whose centre is within 0.02 m of the tower axis
    (and in the zone); ``accept(level, obj_id)`` may restrict which object may sit at which level
    (level 0 = bottom).  Used for progress: the result is a valid :func:`is_stack` sequence.
    """
    pool = [i for i in ids if not toppled(state, i) and (zone_id is None or in_zone(state, i, zone_id))]
    best: list[int] = []
    for b in pool:
        if not resting_on_table(state, b) or (accept is not None and not accept(0, b)):
            continue
        tower = [b]
        axis = state.pos(b)[:2]
        left = [i for i in pool if i != b]
        while True:
            top = tower[-1]
            cands = []
            for c in left:
                pc = state.pos(c)
                if math.hypot(pc[0] - axis[0], pc[1] - axis[1]) > STACK_AXIS_TOL:
                    continue
                gap = (state.spec(c).height + state.spec(top).height) / 2
                err = abs(float(pc[2] - state.pos(top)[2]) - gap)
                if err > Z_TOL or (accept is not None and not accept(len(tower), c)):
                    continue
                cands.append((err, c))
            if not cands:
                break
            nxt = min(cands)[1]
            tower.append(nxt)
            left.remove(nxt)
        if len(tower) > len(best):
            best = tower
    return best


# --------------------------------------------------------------------------------------- motion
def moved_less_than(state: SceneState, obj_id: int, start_pos: Vector, tol: float = MOVE_TOL) -> bool:
    """Whether the object's centre ends within ``tol`` (default 0.03 m, 3-D distance) of
    ``start_pos``."""
    return float(np.linalg.norm(state.pos(obj_id) - np.asarray(start_pos, dtype=float))) <= tol


# --------------------------------------------------------------------------------------- shapes
def fit_circle(points: Sequence[Vector]) -> tuple[np.ndarray, float, float]:
    """Least-squares circle through the xy of ``points``: ``(centre_xy, radius, max_residual)``.

    ``max_residual`` is the largest |distance to centre − radius| (m).  Fewer than three points or
    collinear points give ``radius = max_residual = inf``.
    """
    p = np.asarray(points, dtype=float).reshape(len(points), -1)[:, :2] if len(points) else np.zeros((0, 2))
    if len(p) < 3:
        return (p.mean(axis=0) if len(p) else np.zeros(2)), math.inf, math.inf
    # Kasa fit on centred coordinates: x² + y² + D x + E y + F = 0.
    m = p.mean(axis=0)
    q = p - m
    a = np.column_stack([q[:, 0], q[:, 1], np.ones(len(q))])
    b = -(q ** 2).sum(axis=1)
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    if np.linalg.matrix_rank(a) < 3:
        return m, math.inf, math.inf
    cx, cy = -sol[0] / 2, -sol[1] / 2
    r2 = cx * cx + cy * cy - sol[2]
    if not np.isfinite(r2) or r2 <= 0:
        return m, math.inf, math.inf
    r = math.sqrt(r2)
    if r > 1e3:  # numerically collinear
        return m, math.inf, math.inf
    centre = np.array([cx, cy]) + m
    resid = np.abs(np.hypot(p[:, 0] - centre[0], p[:, 1] - centre[1]) - r)
    return centre, float(r), float(resid.max())


def is_grid(
    points: Sequence[Vector],
    rows: int,
    cols: int,
    pitch_range: tuple[float, float] = (0.04, 0.06),
    align_tol: float = Z_TOL,
) -> tuple[bool, str]:
    """Whether the xy of ``points`` form a ``rows × cols`` grid at any orientation.

    Neighbour centre distances along rows and columns must lie in ``pitch_range`` (m) and every
    row and every column must be aligned within ``align_tol`` (m): the spread of the points'
    coordinate across the row (column) direction.  The grid's axes are estimated from the
    nearest-neighbour directions (modulo 90°); both row/column assignments are tried.
    """
    p = np.asarray(points, dtype=float).reshape(len(points), -1)[:, :2] if len(points) else np.zeros((0, 2))
    n = rows * cols
    if len(p) != n:
        return False, f"expected {n} points for a {rows}x{cols} grid, got {len(p)}"
    if n == 1:
        return True, "single point"
    d = np.hypot(p[:, None, 0] - p[None, :, 0], p[:, None, 1] - p[None, :, 1])
    np.fill_diagonal(d, np.inf)
    nn = d.argmin(axis=1)
    v = p[nn] - p
    ang = np.arctan2(v[:, 1], v[:, 0])
    theta = math.atan2(np.sin(4 * ang).sum(), np.cos(4 * ang).sum()) / 4
    local = to_frame_2d(p, theta)
    reasons = []
    for r_, c_, lc in ((rows, cols, local), (cols, rows, local[:, ::-1]),
                       (rows, cols, local[:, ::-1]), (cols, rows, local)):
        ok, why = _check_axis_grid(lc, r_, c_, pitch_range, align_tol)
        if ok:
            return True, f"{rows}x{cols} grid"
        reasons.append(why)
    return False, reasons[0]


def _check_axis_grid(lc: np.ndarray, rows: int, cols: int, pitch: tuple[float, float], tol: float) -> tuple[bool, str]:
    """Grid check in a frame where rows run along local x (rows differ in local y)."""
    order = np.argsort(lc[:, 1], kind="stable")
    grid = lc[order].reshape(rows, cols, 2)
    grid = np.take_along_axis(grid, np.argsort(grid[:, :, 0], axis=1, kind="stable")[:, :, None], axis=1)
    row_spread = np.ptp(grid[:, :, 1], axis=1)
    if np.any(row_spread > tol):
        return False, f"a row is misaligned by {row_spread.max():.3f} m (max {tol})"
    col_spread = np.ptp(grid[:, :, 0], axis=0)
    if np.any(col_spread > tol):
        return False, f"a column is misaligned by {col_spread.max():.3f} m (max {tol})"
    lo, hi = pitch
    if cols > 1:
        dr = np.hypot(*np.moveaxis(np.diff(grid, axis=1), -1, 0))
        if dr.min() < lo or dr.max() > hi:
            return False, f"row pitch {dr.min():.3f}–{dr.max():.3f} m outside {lo}–{hi}"
    if rows > 1:
        dc = np.hypot(*np.moveaxis(np.diff(grid, axis=0), -1, 0))
        if dc.min() < lo or dc.max() > hi:
            return False, f"column pitch {dc.min():.3f}–{dc.max():.3f} m outside {lo}–{hi}"
    return True, "grid"


# --------------------------------------------------------------------------------------- reward
def _pose_match(state: SceneState, obj_id: int, goal, target) -> bool:
    p = state.pos(obj_id)
    t = target.pos
    if goal.metric == "zone":
        half = goal.zone_size / 2
        lx, ly = to_frame_2d(p[:2], target.yaw or 0.0, t[:2])
        return abs(lx) <= half and abs(ly) <= half
    if math.hypot(p[0] - t[0], p[1] - t[1]) > goal.tolerance or abs(p[2] - t[2]) > Z_TOL:
        return False
    if goal.rotations and target.yaw is not None:
        sym = math.pi / 2 if state.spec(obj_id).kind == "block" else 2 * math.pi
        err = (state.poses[obj_id].yaw - target.yaw) % sym
        if min(err, sym - err) > YAW_TOL:
            return False
    return True


def max_matching(adj: Sequence[Sequence[int]], n_targets: int) -> int:
    """Size of a maximum bipartite matching of objects to targets, ``adj[i]`` listing the targets
    (``0 <= j < n_targets``) object ``i`` may take (Kuhn's augmenting paths; goals are small)."""
    owner = [-1] * n_targets

    def augment(i: int, seen: list[bool]) -> bool:
        for j in adj[i]:
            if seen[j]:
                continue
            seen[j] = True
            if owner[j] < 0 or augment(owner[j], seen):
                owner[j] = i
                return True
        return False

    return sum(augment(i, [False] * n_targets) for i in range(len(adj)))


def ravens_reward(goals: Sequence, state: SceneState) -> float:
    """Ravens-style matching reward in [0, 1] over the final state.

    Each object of each goal that sits at a target it may go to counts one; the reward is the
    count divided by the total number of objects over all goals.  Assignment is one-to-one within
    a goal (a maximum matching, so two objects never share one slot) unless the goal has
    ``replace``.  Pose metric: xy within ``goal.tolerance`` and z within 0.015 m of the target
    (and, with ``rotations`` and a target yaw, yaw within 15° modulo the block's 90° symmetry);
    zone metric: centre inside the square of side ``goal.zone_size`` around the target (rotated
    by the target yaw when given).  Goals with no objects are ignored; no goals give 0.
    """
    total = 0
    matched = 0
    for g in goals:
        if not g.objects:
            continue
        total += len(g.objects)
        adj = [[j for j, t in enumerate(g.targets) if g.matches[i][j] and _pose_match(state, oid, g, t)]
               for i, oid in enumerate(g.objects)]
        matched += sum(1 for a in adj if a) if g.replace else max_matching(adj, len(g.targets))
    return matched / total if total else 0.0


# --------------------------------------------------------------------------------------- labels
def short_label(spec: ObjectSpec) -> str:
    """Short diagnostic name, e.g. ``"big red block 3"``, ``"green zone 1"``."""
    size = f"{spec.size} " if spec.kind == "block" and spec.size else ""
    return f"{size}{spec.color} {spec.kind} {spec.obj_id}"


def positions(state: SceneState, ids: Iterable[int]) -> Mapping[int, np.ndarray]:
    """``{id: centre}`` for the given ids."""
    return {i: state.pos(i) for i in ids}


__all__ = [
    "AREA_NAMES", "BOWL_TOL", "MOVE_TOL", "PLANE_TOL", "QUADRANTS", "STACK_AXIS_TOL", "TILT_TOL", "YAW_TOL",
    "Z_TOL", "WORKSPACE_X", "WORKSPACE_Y", "WORKSPACE_Z",
    "area_bounds", "bowl_floor_z", "bowl_rim_z", "build_tower", "find_stack_order", "fit_circle", "in_area",
    "in_bowl", "in_square", "in_zone", "is_grid", "is_stack", "max_matching", "moved_less_than", "objects_in_zone", "positions",
    "ravens_reward", "resting_on", "resting_on_table", "short_label", "toppled", "zone_half_size",
    "zone_local_xy", "zone_outside_distance",
]


# ======================================================================================= generated 6–10
# Checks of the generated tasks 6–10 (stack groups, zone counts, rows on a line, fixture slots).
# Kept in one appended section (with its own imports and ``__all__`` extension) so the halves of
# issue 8 merge cleanly.
from dataclasses import dataclass as _dataclass  # noqa: E402

from capmj.sim.objects import BLOCK_SIZES, FIXTURE_HEIGHT, FIXTURE_LONG, FIXTURE_WALL  # noqa: E402

FIXTURE_SLOT = BLOCK_SIZES["small"]
"""Slot pitch ``a`` (m) of an L-fixture: the slots hold small blocks.  Must equal the ``a`` of
``capmj.sim.scene._add_fixture``, whose body origin is the centre of slot (0, 0)."""
FIXTURE_SLOTS_LOCAL: tuple[tuple[float, float, float], ...] = (
    (0.0, 0.0, 0.0), (FIXTURE_SLOT, 0.0, 0.0), (0.0, FIXTURE_SLOT, 0.0))
"""The three slots in the fixture frame (spec task 10): along the long wall, then the short one."""
FIXTURE_RADIUS = math.hypot(FIXTURE_LONG - FIXTURE_SLOT / 2 - FIXTURE_WALL, FIXTURE_SLOT / 2 + FIXTURE_WALL)
"""Distance (m) from the fixture origin bounding its farthest point (the outer end of the long wall,
local (0.067, −0.033) with the walls ``FIXTURE_CLEARANCE`` out; the bound is that of walls
touching the slots, kept so scenes stay as they were); larger than ``ObjectSpec.footprint_radius``,
which assumes a centred box."""
SLOT_TOL = 0.012
"""A block fills a slot when its centre is within this distance (m, 3-D) of the slot centre."""
ROW_LINE_TOL = 0.015
"""Row blocks: centre within this distance (m) of the line."""
ROW_PITCH_TOL = 0.015
"""Row blocks: neighbour centre spacing within this (m) of the required pitch."""
ROW_MID_TOL = 0.02
"""Row blocks: the mean of the centres within this distance (m) of the required midpoint."""


def largest_odd_at_most(n: int) -> int:
    """The largest odd number ≤ ``n`` (0 when ``n`` < 1)."""
    return n if n % 2 == 1 else max(n - 1, 0)


def zone_color_counts(state: SceneState, zone_id: int) -> dict[str, list[int]]:
    """``{colour: [block ids]}`` of the blocks whose centre is in the zone (see :func:`in_zone`)."""
    out: dict[str, list[int]] = {}
    for i in objects_in_zone(state, zone_id):
        out.setdefault(state.spec(i).color, []).append(i)
    return out


@_dataclass(frozen=True)
class ZoneStack:
    """The blocks of one zone seen as a stack: ``members`` are the given blocks whose centre is in
    the zone, ``tower`` the tallest valid stack among them (bottom first), ``ok`` whether all
    members form that one stack, ``why`` the reason when not."""

    zone: int
    members: tuple[int, ...]
    tower: tuple[int, ...]
    ok: bool
    why: str


def zone_stacks(state: SceneState, zone_ids: Sequence[int], ids: Iterable[int]) -> list[ZoneStack]:
    """For each zone, whether the blocks of ``ids`` lying in it form exactly one stack.

    A zone with no block is not ok ("empty").  Stack rules are :func:`is_stack`'s (axis 0.02 m,
    z gaps ± 0.015 m, tilt ≤ 15°, the bottom on the table).
    """
    ids = list(ids)
    out = []
    for z in zone_ids:
        members = [i for i in ids if in_zone(state, i, z)]
        tower = build_tower(state, members, z)
        if not members:
            ok, why = False, "empty"
        else:
            ok, why = is_stack(state, find_stack_order(state, members))
            ok = ok and len(tower) == len(members)
            if not ok and len(tower) < len(members) and why.endswith("stacked"):
                why = f"{len(members) - len(tower)} block(s) in the zone are not on its stack"
        out.append(ZoneStack(z, tuple(members), tuple(tower), ok, why))
    return out


def group_sizes(n: int, k: int) -> list[int]:
    """Sizes of ``n`` items divided into groups of ``k`` (the last one smaller when k ∤ n),
    largest first."""
    return [k] * (n // k) + ([n % k] if n % k else [])


@_dataclass(frozen=True)
class RowReport:
    """How well points form an evenly spaced row along a line (see :func:`row_on_line`).

    ``order`` are the input indices sorted along the line, ``offsets`` each point's distance from
    the line (input order), ``gaps`` the centre distances of neighbours in row order,
    ``midpoint_error`` the distance from the mean of the points to the required midpoint.
    """

    ok: bool
    order: tuple[int, ...]
    offsets: tuple[float, ...]
    gaps: tuple[float, ...]
    midpoint_error: float
    reasons: tuple[str, ...]


def row_on_line(
    points: Sequence[Vector],
    line_point: Vector,
    line_dir: Vector,
    pitch: float,
    *,
    line_tol: float = ROW_LINE_TOL,
    pitch_tol: float = ROW_PITCH_TOL,
    mid_tol: float = ROW_MID_TOL,
) -> RowReport:
    """Whether the xy of ``points`` lie on the line through ``line_point`` along ``line_dir``,
    evenly spaced and centred on ``line_point``.

    Tolerances: every centre within ``line_tol`` (0.015 m) of the line; every neighbour centre
    distance (in order along the line) within ``pitch_tol`` (0.015 m) of ``pitch``; the mean of
    the centres within ``mid_tol`` (0.02 m) of ``line_point``.  Reasons name point indices.
    """
    p = np.asarray(points, dtype=float).reshape(len(points), -1)[:, :2] if len(points) else np.zeros((0, 2))
    c = np.asarray(line_point, dtype=float)[:2]
    e = np.asarray(line_dir, dtype=float)[:2]
    e = e / np.linalg.norm(e)
    n = np.array([-e[1], e[0]])
    along = (p - c) @ e
    offsets = np.abs((p - c) @ n)
    order = np.argsort(along, kind="stable")
    gaps = np.hypot(*np.diff(p[order], axis=0).T) if len(p) > 1 else np.zeros(0)
    mid = float(np.hypot(*(p.mean(axis=0) - c))) if len(p) else math.inf
    reasons = [f"point {i} is {offsets[i]:.3f} m off the line (max {line_tol})"
               for i in range(len(p)) if offsets[i] > line_tol]
    reasons += [f"points {order[k]} and {order[k + 1]} are {g:.3f} m apart (need {pitch:.3f} ± {pitch_tol})"
                for k, g in enumerate(gaps) if abs(g - pitch) > pitch_tol]
    if mid > mid_tol:
        reasons.append(f"the row's midpoint is {mid:.3f} m from the required midpoint (max {mid_tol})")
    return RowReport(not reasons and len(p) > 0, tuple(int(i) for i in order), tuple(float(v) for v in offsets),
                     tuple(float(g) for g in gaps), mid, tuple(reasons))


def fixture_slots(origin: Vector, yaw: float) -> np.ndarray:
    """(3, 3) world centres of a small block in each slot of an L-fixture whose origin (slot
    (0, 0), as ``get_obj_pos`` reports it) is ``origin`` and whose yaw is ``yaw``.

    The slot z is the table (``origin`` z − FIXTURE_HEIGHT/2) plus half a block.  The walls keep
    ``capmj.sim.objects.FIXTURE_CLEARANCE`` from these footprints, so a block lowered exactly
    here does not scrape them.
    """
    o = np.asarray(origin, dtype=float)
    z = float(o[2]) - FIXTURE_HEIGHT / 2 + FIXTURE_SLOT / 2
    xy = from_frame_2d([(u, v) for u, v, _ in FIXTURE_SLOTS_LOCAL], yaw, o[:2])
    return np.column_stack([xy, np.full(len(xy), z)])


def slot_occupants(state: SceneState, fixture_id: int, ids: Iterable[int], tol: float = SLOT_TOL) -> list[int | None]:
    """Per slot of the fixture, the upright block of ``ids`` whose centre is within ``tol``
    (0.012 m, 3-D) of the slot centre (the nearest one), else None."""
    slots = fixture_slots(state.pos(fixture_id), state.poses[fixture_id].yaw)
    out: list[int | None] = []
    for s in slots:
        best = min(((float(np.linalg.norm(state.pos(i) - s)), i) for i in ids if not toppled(state, i)), default=None)
        out.append(best[1] if best is not None and best[0] <= tol else None)
    return out


__all__ += [
    "FIXTURE_RADIUS", "FIXTURE_SLOT", "FIXTURE_SLOTS_LOCAL", "ROW_LINE_TOL", "ROW_MID_TOL", "ROW_PITCH_TOL",
    "RowReport", "SLOT_TOL", "ZoneStack", "fixture_slots", "group_sizes", "largest_odd_at_most", "row_on_line",
    "slot_occupants", "zone_color_counts", "zone_stacks",
]


# ======================================================================================= generated
# Layouts of the generated tasks 1–5 (pyramid, cube, circles, concentric circles).  Footprints are
# the objects' real oriented squares (shapely), so "touching" and "inside the zone" mean what a
# reader of the final snapshot would see, not a bounding circle.
TOUCH_GAP = 0.001
"""Two footprints closer than this (m) touch."""
CIRCLE_TOL = 0.01
"""Every centre of a circle lies within this distance (m) of the fitted circle."""
CENTRE_TOL = 0.02
"""Two circles (or a circle and the ball) are concentric when their centres are this close (m)."""


def footprint(state: SceneState, obj_id: int):
    """The object's footprint on the table as a shapely geometry: capmj's one footprint model
    (:func:`capmj.sim.footprint.shape`, the planner API's too) at its pose in ``state`` — its
    oriented rectangle at the current yaw (a fixture: its two walls; tilted more than 15°: its
    world xy box), a disc for balls and bowls."""
    return _footprint.shape(state.spec(obj_id), state.poses[obj_id])


def touching_pairs(state: SceneState, ids: Sequence[int], gap: float = TOUCH_GAP) -> list[tuple[int, int, float]]:
    """Pairs ``(a, b, distance)`` of the objects whose footprints are closer than ``gap`` (m)."""
    fps = {i: footprint(state, i) for i in ids}
    ids = list(ids)
    return [(a, b, float(fps[a].distance(fps[b])))
            for k, a in enumerate(ids) for b in ids[k + 1:] if fps[a].distance(fps[b]) < gap]


def supporters(state: SceneState, upper: int, lowers: Iterable[int], tol: float = Z_TOL) -> list[int]:
    """The objects of ``lowers`` that ``upper`` rests on: the z gap of their centres is the mean of
    the two heights ± 0.015 m and their footprints overlap (area > 1 mm²)."""
    fu = footprint(state, upper)
    out = []
    for lo in lowers:
        gap = (state.spec(upper).height + state.spec(lo).height) / 2
        if abs(float(state.pos(upper)[2] - state.pos(lo)[2]) - gap) <= tol and fu.intersection(footprint(state, lo)).area > 1e-6:
            out.append(lo)
    return out


def is_layer(state: SceneState, ids: Sequence[int], rows: int, cols: int, level: int,
             pitch_range: tuple[float, float], align_tol: float = Z_TOL) -> tuple[bool, str]:
    """Whether the blocks form one ``rows × cols`` grid layer (:func:`is_grid`: neighbour pitch in
    ``pitch_range``, rows and columns aligned within ``align_tol``) at height ``level`` (0 = on the
    table: every centre at (level + ½) block heights ± 0.015 m), none tilted more than 15°."""
    for i in ids:
        if toppled(state, i):
            return False, f"{short_label(state.spec(i))} is tilted {math.degrees(state.poses[i].tilt):.0f}° (max 15°)"
        h = state.spec(i).height
        z = float(state.pos(i)[2])
        if abs(z - (level + 0.5) * h) > Z_TOL:
            return False, f"{short_label(state.spec(i))} is at z = {z:.3f} m, not on layer {level + 1} ({(level + 0.5) * h:.3f} ± {Z_TOL})"
    return is_grid([state.pos(i) for i in ids], rows, cols, pitch_range, align_tol)


def circle_of(state: SceneState, ids: Sequence[int], tol: float = CIRCLE_TOL,
              min_radius: float = 0.0) -> tuple[bool, np.ndarray, float, str]:
    """Whether the xy centres of ``ids`` lie on one circle: ``(ok, centre, radius, reason)``.

    The circle is the least-squares fit (:func:`fit_circle`); every centre must be within ``tol``
    (0.01 m) of it and the radius at least ``min_radius`` (m)."""
    c, r, res = fit_circle([state.pos(i) for i in ids])
    if not math.isfinite(r):
        return False, c, r, f"{len(ids)} centres do not span a circle (fewer than 3 or collinear)"
    if res > tol:
        d = [abs(math.hypot(*(state.pos(i)[:2] - c)) - r) for i in ids]
        worst = ids[int(np.argmax(d))]
        return False, c, r, (f"{short_label(state.spec(worst))} is {max(d):.3f} m off the fitted circle "
                             f"(radius {r:.3f} m, max {tol})")
    if r < min_radius:
        return False, c, r, f"circle radius {r:.3f} m is below {min_radius:.3f} m"
    return True, c, r, f"circle of radius {r:.3f} m at ({c[0]:.3f}, {c[1]:.3f})"


def angular_order(state: SceneState, ids: Sequence[int], centre: Vector) -> list[int]:
    """``ids`` sorted by the angle of their xy centre around ``centre``."""
    return sorted(ids, key=lambda i: math.atan2(state.pos(i)[1] - centre[1], state.pos(i)[0] - centre[0]))


def alternates(state: SceneState, ids: Sequence[int], centre: Vector) -> tuple[bool, str]:
    """Whether colours alternate going round ``centre`` (cyclically: two colours, equal counts,
    no two angular neighbours of one colour); the reason names a same-coloured neighbour pair."""
    order = angular_order(state, ids, centre)
    colours = {state.spec(i).color for i in ids}
    if len(colours) != 2:
        return False, f"alternation needs exactly two colours, got {', '.join(sorted(colours))}"
    for a, b in zip(order, order[1:] + order[:1]):
        if state.spec(a).color == state.spec(b).color:
            return False, f"{short_label(state.spec(a))} and {short_label(state.spec(b))} are neighbours of the same colour"
    return True, "colours alternate"


def concentric(state: SceneState, ring_a: Sequence[int], ring_b: Sequence[int], centre_tol: float = CENTRE_TOL,
               min_gap: float = 0.04, tol: float = CIRCLE_TOL) -> tuple[bool, str]:
    """Whether ``ring_a`` and ``ring_b`` each lie on a circle (:func:`circle_of`, ``tol``), the two
    centres within ``centre_tol`` (0.02 m) and the radii at least ``min_gap`` (m) apart."""
    ok_a, ca, ra, why_a = circle_of(state, ring_a, tol)
    if not ok_a:
        return False, why_a
    ok_b, cb, rb, why_b = circle_of(state, ring_b, tol)
    if not ok_b:
        return False, why_b
    d = float(np.hypot(*(ca - cb)))
    if d > centre_tol:
        return False, f"the circle centres are {d:.3f} m apart (max {centre_tol})"
    if abs(ra - rb) < min_gap:
        return False, f"the radii {ra:.3f} m and {rb:.3f} m differ by less than {min_gap} m"
    return True, f"concentric circles of radii {min(ra, rb):.3f} m and {max(ra, rb):.3f} m"


__all__ += [
    "CENTRE_TOL", "CIRCLE_TOL", "TOUCH_GAP", "alternates", "angular_order", "circle_of", "concentric", "footprint",
"is_layer", "supporters", "touching_pairs",
]
