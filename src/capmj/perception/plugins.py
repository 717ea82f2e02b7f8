"""Perceivers by name: the built-in one and those other packages declare as ``capmj.perceivers``
entry points, so a learned detector (SAM, OWL-ViT, a VLM) plugs in without touching capmj.

A perception mode names what the planner API reads: :data:`STATE` (the simulator, no perceiver)
or a perceiver.  :data:`BUILTIN` is ``rgbd`` (:class:`~capmj.perception.ClassicalPerceiver`); it is
defined here rather than as an entry point of capmj's own so that it is there however capmj was
installed.  A third-party package declares, in its ``pyproject.toml``::

    [project.entry-points."capmj.perceivers"]
    owlvit = "my_detector.perceiver:OwlVitPerceiver"

and ``python -m capmj.bench --perception owlvit`` uses it.  The target is a class or a
zero-argument factory (called) or a ready object; what it gives must satisfy
:class:`~capmj.perception.Perceiver` (a ``perceive(bundle)`` method).  Entry points are scanned on
every call (cheap: metadata only), and a plugin is imported only when its name is asked for.
"""

from __future__ import annotations

import inspect
from importlib import metadata
from typing import Any, Callable

from capmj.errors import ConfigError, PluginError
from capmj.perception.perceiver import ClassicalPerceiver, Perceiver

__all__ = ["BUILTIN", "GROUP", "STATE", "check_mode", "load_perceiver", "perception_modes"]

GROUP = "capmj.perceivers"
STATE = "state"
"""The mode without a perceiver: the planner API reads the simulator (the default)."""
BUILTIN: dict[str, Callable[[], Perceiver]] = {"rgbd": ClassicalPerceiver}
"""capmj's own perceivers by mode name."""


def _entry_points() -> dict[str, metadata.EntryPoint]:
    return {ep.name: ep for ep in metadata.entry_points(group=GROUP)}


def perception_modes() -> tuple[str, ...]:
    """Every valid perception mode: ``state``, the built-in perceivers, then the plugins (sorted)."""
    plugins = sorted(set(_entry_points()) - {STATE, *BUILTIN})
    return (STATE, *BUILTIN, *plugins)


def _unknown(name: str) -> ConfigError:
    return ConfigError(f"unknown perception mode {name!r}; valid modes: {', '.join(perception_modes())}")


def check_mode(name: str) -> str:
    """``name`` if it is a perception mode, else a :class:`ConfigError` naming the valid ones."""
    if name not in perception_modes():
        raise _unknown(name)
    return name


def load_perceiver(name: str) -> Perceiver:
    """The perceiver of mode ``name`` (``state`` has none: a ConfigError, as for unknown names)."""
    if name in BUILTIN:
        return BUILTIN[name]()
    eps = _entry_points()
    if name == STATE or name not in eps:
        raise _unknown(name)
    ep = eps[name]
    dist = getattr(ep, "dist", None)
    where = f"perceiver {name!r} ({ep.value}, from {dist.metadata['Name'] if dist is not None else 'an unknown package'})"
    try:
        target: Any = ep.load()
        obj = target() if inspect.isclass(target) or (callable(target) and not hasattr(target, "perceive")) else target
    except Exception as exc:  # noqa: BLE001 - a broken plugin is named, not a traceback three modules later
        raise PluginError(f"{where} failed to load: {type(exc).__name__}: {exc}") from exc
    if not callable(getattr(obj, "perceive", None)):
        raise PluginError(f"{where} is not a Perceiver: it has no perceive(bundle) method")
    return obj
