"""Short names and positions for the reasons a verdict gives ("big red block 3 is tilted …")."""

from __future__ import annotations

from typing import Iterable, Mapping

import numpy as np

from capmj.sim.objects import ObjectSpec
from capmj.sim.state import SceneState


def short_label(spec: ObjectSpec) -> str:
    """Short diagnostic name, e.g. ``"big red block 3"``, ``"green zone 1"``."""
    size = f"{spec.size} " if spec.kind == "block" and spec.size else ""
    return f"{size}{spec.color} {spec.kind} {spec.obj_id}"


def positions(state: SceneState, ids: Iterable[int]) -> Mapping[int, np.ndarray]:
    """``{id: centre}`` for the given ids."""
    return {i: state.pos(i) for i in ids}


__all__ = ["positions", "short_label"]
