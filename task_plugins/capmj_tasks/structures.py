"""Shared code of the generated construction tasks 1–5: target layouts and their judgement.

Targets: layered grids (the 9-4-1 pyramid, the 2×2×2 cube) and rings of blocks.  Rings keep each
block turned radially, which fixes how much of the chord two neighbours take, so the radius that
keeps a given gap follows from the block count alone (:func:`ring_radius`).  The checks turn a
final state into layers by height and judge each layer with the shared predicates
(:func:`capmj.tasks.predicates.is_layer`, :func:`~capmj.tasks.predicates.supporters`, …).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

from capmj.sim.objects import BLOCK_SIZES
from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Target

from capmj_tasks.common import label

BLOCK = BLOCK_SIZES["small"]
RING_GAP = 0.01
"""Free distance (m) the oracle leaves between the faces of two neighbours on a ring."""
ABOVE_TOL = 0.015
"""A cube's upper block is "above" a lower one when their xy centres are this close (m)."""


# --------------------------------------------------------------------------------------- targets
def grid_points(centre: Sequence[float], yaw: float, rows: int, cols: int, pitch: float) -> list[tuple[float, float]]:
    """xy of a ``rows × cols`` grid of pitch ``pitch`` centred on ``centre``, turned by ``yaw``."""
    cs, sn = math.cos(yaw), math.sin(yaw)
    out = []
    for i in range(rows):
        for j in range(cols):
            u, v = (j - (cols - 1) / 2) * pitch, (i - (rows - 1) / 2) * pitch
            out.append((float(centre[0] + cs * u - sn * v), float(centre[1] + sn * u + cs * v)))
    return out


def layer_goal(ids: Sequence[int], centre: Sequence[float], yaw: float, side: int, level: int,
               pitch: float) -> OracleGoal:
    """One goal: the blocks ``ids`` onto the ``side × side`` grid of layer ``level`` (0 = table), any
    block on any cell, turned to the grid's yaw."""
    z = (level + 0.5) * BLOCK
    targets = tuple(Target((x, y, z), yaw) for x, y in grid_points(centre, yaw, side, side, pitch))
    return OracleGoal(tuple(ids), targets, tuple((1,) * len(targets) for _ in ids), metric="pose", tolerance=P.PLANE_TOL)


def ring_radius(n: int, gap: float = RING_GAP, min_radius: float = 0.0, block: float = BLOCK) -> float:
    """Smallest radius (m) of a ring of ``n`` radially turned blocks with ``gap`` between neighbours.

    Two neighbours' facing sides meet the chord at π/n, so each takes ``block/2 (cos π/n + sin π/n)``
    of it."""
    a = math.pi / n
    return max(min_radius, (block * (math.cos(a) + math.sin(a)) + gap) / (2 * math.sin(a)))


def ring_targets(centre: Sequence[float], radius: float, n: int, phase: float = 0.0) -> list[Target]:
    """``n`` block targets evenly on a circle, each turned radially (yaw = its angle)."""
    out = []
    for k in range(n):
        a = phase + 2 * math.pi * k / n
        out.append(Target((float(centre[0] + radius * math.cos(a)), float(centre[1] + radius * math.sin(a)), BLOCK / 2), a))
    return out


def colour_goal(scene: Scene, ids: Sequence[int], targets: Sequence[Target], colours: Sequence[str]) -> OracleGoal:
    """One goal: each block may take any target of its own colour (``colours[j]`` of target j)."""
    matches = tuple(tuple(int(scene.by_id(i).color == c) for c in colours) for i in ids)
    return OracleGoal(tuple(ids), tuple(targets), matches, metric="pose", tolerance=P.PLANE_TOL)


# --------------------------------------------------------------------------------------- checks
@dataclass
class Judgement:
    """Conditions met / total and the diagnostics of one final state."""

    met: float = 0.0
    total: float = 0.0
    diagnostics: list[str] = field(default_factory=list)

    def check(self, ok: bool, why: str, weight: float = 1.0) -> bool:
        """Count one condition; its diagnostic ``why`` is kept when it fails."""
        self.total += weight
        if ok:
            self.met += weight
        elif why:
            self.diagnostics.append(why)
        return ok

    def partial(self, met: float, total: float) -> None:
        """Count ``met`` of ``total`` units without a diagnostic of its own."""
        self.met += met
        self.total += total

    @property
    def ok(self) -> bool:
        return self.met >= self.total


def level_of(state: SceneState, obj_id: int) -> int | None:
    """The layer an upright block's centre height puts it on (0 = table), None between layers."""
    if P.toppled(state, obj_id):
        return None
    h = state.spec(obj_id).height
    z = float(state.pos(obj_id)[2])
    lvl = int(round(z / h - 0.5))
    return lvl if lvl >= 0 and abs(z - (lvl + 0.5) * h) <= P.Z_TOL else None


def where(state: SceneState, obj_id: int) -> str:
    p = state.pos(obj_id)
    return f"at ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f})"


def check_layers(state: SceneState, ids: Sequence[int], zone_id: int, sides: Sequence[int],
                 pitch: tuple[float, float], stacked: bool, j: Judgement) -> None:
    """Judge blocks built into layers of ``sides[k] × sides[k]`` grids inside the zone.

    Layer k holds the blocks whose centre is in the zone at height (k + ½) block.  Each layer
    must have the right count and be a grid (:func:`predicates.is_layer`, ``pitch``, alignment
    0.015 m).  Above the first, each block rests on the layer below: on exactly one block within
    0.015 m in xy when ``stacked`` (cube), else on four (a pyramid's block centred on four).
    "In the zone" is the one rule of every task (:func:`predicates.in_zone`: the centre inside the
    zone square), for every layer.
    """
    zone = state.spec(zone_id)
    zname = label(zone)
    layers: list[list[int]] = [[] for _ in sides]
    for i in ids:
        lvl = level_of(state, i)
        if lvl is not None and lvl < len(sides) and P.in_zone(state, i, zone_id):
            layers[lvl].append(i)
        elif P.toppled(state, i):
            j.diagnostics.append(f"{label(state.spec(i))} is tilted {math.degrees(state.poses[i].tilt):.0f}° (max 15°)")
        elif not P.in_zone(state, i, zone_id):
            j.diagnostics.append(f"{label(state.spec(i))} is not in the {zname} "
                                 f"({P.zone_outside_distance(state, i, zone_id):.3f} m outside)")
        else:
            j.diagnostics.append(f"{label(state.spec(i))} is in the {zname} but on no layer {where(state, i)}")
    for k, (side, layer) in enumerate(zip(sides, layers)):
        need = side * side
        if len(layer) != need:
            j.diagnostics.append(f"layer {k + 1} has {len(layer)} block(s), needs {need}")
        j.partial(min(len(layer), need), need)
        grid = P.is_layer(state, layer, side, side, k, pitch) if len(layer) == need else (False, "")
        j.check(grid[0], f"layer {k + 1} is not a {side}x{side} grid: {grid[1]}" if grid[1] else "")
        j.partial(0, max(0, need - len(layer)))  # the missing blocks' placement conditions
        for i in layer:
            if k == 0:
                continue
            below = P.supporters(state, i, layers[k - 1])
            if stacked:
                near = [b for b in below if math.hypot(*(state.pos(i)[:2] - state.pos(b)[:2])) <= ABOVE_TOL]
                j.check(len(near) == 1 and len(below) == 1,
                        f"{label(state.spec(i))} on layer {k + 1} is not right above one block of layer {k} "
                        f"(within {ABOVE_TOL} m in xy, resting on it)")
            else:
                j.check(len(below) == 4, f"{label(state.spec(i))} on layer {k + 1} rests on {len(below)} "
                        f"block(s) of layer {k}, needs 4")


def check_ring_blocks(state: SceneState, ids: Sequence[int], zone_id: int | None, j: Judgement) -> list[int]:
    """Each block upright on the table (and its centre in the zone); returns the blocks that are."""
    good = []
    zname = label(state.spec(zone_id)) if zone_id is not None else ""
    for i in ids:
        if P.toppled(state, i):
            why = f"{label(state.spec(i))} is tilted {math.degrees(state.poses[i].tilt):.0f}° (max 15°)"
        elif not P.resting_on_table(state, i):
            why = f"{label(state.spec(i))} is not on the table {where(state, i)}"
        elif zone_id is not None and not P.in_zone(state, i, zone_id):
            why = f"{label(state.spec(i))} is not in the {zname} ({P.zone_outside_distance(state, i, zone_id):.3f} m outside)"
        else:
            why = ""
        if j.check(not why, why):
            good.append(i)
    return good


__all__ = [
    "ABOVE_TOL", "BLOCK", "Judgement", "RING_GAP", "check_layers", "check_ring_blocks", "colour_goal", "grid_points",
    "layer_goal", "level_of", "ring_radius", "ring_targets",
]
