"""What the planner API accepts as a value, and how it shows one: positions, poses, normalised
workspace coordinates, call-log summaries.

Shared by :mod:`capmj.agents.api.planner_api` (capmj's functions) and :mod:`capmj.agents.api.capravens`
(CapRavens' names), so both read a position, a pose and a normalised point the same way.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from capmj.agents.sandbox.ravens_utils import ONE_ELEMENT_LISTS, Coordinate
from capmj.agents.sandbox.sizes import preview
from capmj.sim.bounds import WORKSPACE

__all__ = ["ONE_ELEMENT_LISTS", "Coordinate", "denormalize_uv", "is_number", "is_pose", "is_vector", "summary"]


def denormalize_uv(u: float, v: float) -> tuple[float, float]:
    """Normalised workspace coordinates → world xy: u left→right, v bottom→top of the image
    (x = 0.75 − 0.5 v, y = −0.5 + u on :data:`capmj.sim.bounds.WORKSPACE`)."""
    w = WORKSPACE
    return w.xmax - (w.xmax - w.xmin) * float(v), w.ymin + (w.ymax - w.ymin) * float(u)


def is_number(v: Any) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def is_vector(v: Any, lengths: tuple[int, ...] = (2, 3)) -> bool:
    """A flat list, tuple or array of ``lengths`` numbers (default: a position [x, y(, z)])."""
    if isinstance(v, np.ndarray):
        return v.ndim == 1 and len(v) in lengths and np.issubdtype(v.dtype, np.number)
    return isinstance(v, (list, tuple)) and len(v) in lengths and all(is_number(x) for x in v)


def is_pose(v: Any) -> bool:
    """``(position, quaternion xyzw)``."""
    return (isinstance(v, (list, tuple)) and len(v) == 2 and is_vector(v[0]) and is_vector(v[1], (4,)))


def summary(value: Any, limit: int = 160) -> str:
    """A value as the call log and error messages show it: rounded, at most ``limit`` characters
    (and never more made: a plan value's full text can be huge, see :func:`~capmj.agents.sandbox.sizes.preview`)."""
    if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
        text = np.array2string(np.round(value, 4), separator=", ", threshold=20)
    elif isinstance(value, float):
        text = f"{value:.4f}"
    elif isinstance(value, (list, tuple)) and value and all(isinstance(v, float) for v in value[:limit]):
        shown = value[: limit // 3 + 1]  # a float takes at least 3 characters: enough to fill the limit
        text = "[" + ", ".join(f"{v:.4f}" for v in shown) + ("]" if len(shown) == len(value) else ", ...")
    else:
        text = preview(value, limit)
    return text if len(text) <= limit else text[: limit - 3] + "..."
