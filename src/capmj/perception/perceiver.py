"""The perceiver: calibrated RGB-D views in, detected objects out.

:class:`Perceiver` is a protocol so that a learned detector can replace the built-in one;
:class:`ClassicalPerceiver` is the built-in one: fuse the views into a top-down map
(:mod:`~capmj.perception.cloud`), cut it into single-colour surfaces
(:mod:`~capmj.perception.segment`), and fit an object to each (:mod:`~capmj.perception.detect`).
Everything is deterministic numpy/scipy on the CPU: the same images give the same detections
in any process, with no random state at all.

Detections come in a stable order that depends only on what is seen: fixed objects first, then
movable ones (every task spawns its zones, bowls, balls and fixtures before its blocks, so the
state API and every prompt example number fixed objects first; a small planner model copies
``'fixed green zone with obj_id 1'`` from the examples, and numbering blocks first made that an
unknown object in rgbd mode only); within each group by kind (the catalogue's order), then by
position along x, then y, rounded to 5 mm so that a millimetre of noise does not reorder two
objects; ids assigned in this order are therefore stable across re-renders of one scene.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from capmj.perception.cloud import CELL, TopDownMap, fuse
from capmj.perception.detect import Detection, detect
from capmj.perception.rgbd import RGBDBundle
from capmj.perception.segment import segment
from capmj.sim.objects import KINDS


class Perceiver(Protocol):
    """Anything that turns one RGB-D bundle into detections."""

    def perceive(self, bundle: RGBDBundle) -> tuple[Detection, ...]: ...


def _order(d: Detection) -> tuple[bool, int, int, int]:
    return (not d.fixed, KINDS.index(d.kind), round(d.position[0] / 0.005), round(d.position[1] / 0.005))


@dataclass(frozen=True)
class ClassicalPerceiver:
    """Colour segmentation on the fused top-down map, then footprint fitting (see the module docstring)."""

    cell: float = CELL
    """Edge (m) of the top-down grid's cells."""

    def top_down(self, bundle: RGBDBundle) -> TopDownMap:
        """The fused map this perceiver works on (for inspection and debugging)."""
        return fuse(bundle, self.cell)

    def perceive(self, bundle: RGBDBundle) -> tuple[Detection, ...]:
        found = detect(segment(self.top_down(bundle)), self.cell)
        return tuple(sorted(found, key=_order))


__all__ = ["ClassicalPerceiver", "Perceiver"]
