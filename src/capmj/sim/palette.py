"""Named colours (Ravens/Tableau palette plus the thesis's extras) and warm/cool groups.

The LLM sees colour *names* only, so the names and groups here are part of the benchmark
definition: changing an RGB value changes renders, changing a name changes the task.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Mapping

from capmj.errors import ConfigError

_RGB_255: dict[str, tuple[int, int, int]] = {
    "blue": (78, 121, 167),
    "red": (255, 87, 89),
    "green": (89, 169, 79),
    "orange": (242, 142, 43),
    "yellow": (237, 201, 72),
    "purple": (176, 122, 161),
    "pink": (255, 157, 167),
    "cyan": (118, 183, 178),
    "brown": (156, 117, 95),
    "white": (255, 255, 255),
    "gray": (186, 176, 172),
    "indigo": (75, 0, 130),
    "violet": (143, 0, 255),
    "silver": (192, 192, 192),
    "gold": (255, 215, 0),
    "black": (30, 30, 30),
}

COLORS: Mapping[str, tuple[float, float, float, float]] = MappingProxyType(
    {name: (r / 255.0, g / 255.0, b / 255.0, 1.0) for name, (r, g, b) in _RGB_255.items()}
)
"""Colour name -> RGBA in [0, 1]."""

COLOR_NAMES: tuple[str, ...] = tuple(_RGB_255)
WARM: frozenset[str] = frozenset({"red", "yellow", "orange", "brown", "pink", "gold"})
COOL: frozenset[str] = frozenset({"blue", "green", "cyan", "purple", "gray", "violet", "indigo", "silver"})


def rgba(name: str) -> tuple[float, float, float, float]:
    """RGBA of a colour name; unknown names raise a ``ConfigError`` listing the valid ones."""
    try:
        return COLORS[name]
    except KeyError:
        raise ConfigError(f"unknown colour {name!r}; valid colours: {', '.join(COLOR_NAMES)}") from None
