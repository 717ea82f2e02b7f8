"""Perceivers by name: the built-in one and those other packages declare as ``capmj.perceivers``
entry points, so a learned detector (SAM, OWL-ViT, a VLM) plugs in without touching capmj.

A perception mode names what the planner API reads: :data:`STATE` (the simulator, no perceiver)
or a perceiver.  capmj's own perceiver, ``rgbd`` (:class:`~capmj.perception.ClassicalPerceiver`),
is an entry point of capmj's own ``pyproject.toml`` like any plugin's, so there is one registry
and one way in.  A third-party package declares, in its ``pyproject.toml``::

    [project.entry-points."capmj.perceivers"]
    owlvit = "my_detector.perceiver:OwlVitPerceiver"

and ``python -m capmj.bench --perception owlvit`` uses it.  The target is a class or a
zero-argument factory (called) or a ready object; what it gives must satisfy
:class:`~capmj.perception.Perceiver` (a ``perceive(bundle)`` method).  Entry points are scanned on
every call (cheap: metadata only), and a plugin is imported only when its name is asked for.

Code run from a source tree whose installed metadata predates an entry point of capmj's own (an
editable install made from an older checkout, or ``src/`` on ``PYTHONPATH``) would not see it, so
when the installed metadata declares no perceiver of capmj's, capmj's declarations are read from
the ``pyproject.toml`` of the source tree the code runs from (if there is one): the same
declarations, read where pip would have read them.  Reinstalling (``pip install -e .``) makes the
metadata current.
"""

from __future__ import annotations

import functools
import inspect
import tomllib
from importlib import metadata
from pathlib import Path
from typing import Any

from capmj.errors import ConfigError, PluginError
from capmj.perception.perceiver import Perceiver

__all__ = ["GROUP", "OWN_DIST", "STATE", "check_mode", "declared", "load_perceiver", "perception_modes",
           "source_tree_entry_points"]

GROUP = "capmj.perceivers"
OWN_DIST = "capmj"
"""The distribution whose perceivers are capmj's own (listed first)."""
STATE = "state"
"""The mode without a perceiver: the planner API reads the simulator (the default)."""
_SOURCE_TREE = Path(__file__).resolve().parents[3]
"""The checkout this module lies in when it runs from one (``<root>/src/capmj/perception``)."""


def _dist_name(ep: metadata.EntryPoint) -> str | None:
    dist = getattr(ep, "dist", None)
    return None if dist is None else str(dist.metadata["Name"]).lower()


@functools.cache
def source_tree_entry_points(root: Path = _SOURCE_TREE) -> tuple[metadata.EntryPoint, ...]:
    """capmj's perceivers as the ``pyproject.toml`` at ``root`` declares them; none when ``root``
    holds no pyproject of capmj (an installed wheel)."""
    path = root / "pyproject.toml"
    if not path.is_file():
        return ()
    project = tomllib.loads(path.read_text(encoding="utf-8")).get("project", {})
    if project.get("name") != OWN_DIST:
        return ()
    group = project.get("entry-points", {}).get(GROUP, {})
    return tuple(metadata.EntryPoint(name, value, GROUP) for name, value in group.items())


def declared() -> tuple[dict[str, metadata.EntryPoint], frozenset[str]]:
    """Every declared perceiver by name, and the names that are capmj's own (see the module
    docstring for where capmj's come from when its installed metadata has none)."""
    eps: dict[str, metadata.EntryPoint] = {}
    own: set[str] = set()
    for ep in metadata.entry_points(group=GROUP):
        if _dist_name(ep) == OWN_DIST:
            own.add(ep.name)
        if ep.name not in own or _dist_name(ep) == OWN_DIST:  # a plugin cannot take a name of capmj's
            eps[ep.name] = ep
    if not own:
        for ep in source_tree_entry_points():
            eps[ep.name] = ep
            own.add(ep.name)
    return eps, frozenset(own)


def perception_modes() -> tuple[str, ...]:
    """Every valid perception mode: ``state``, capmj's own perceivers, then the plugins (each sorted)."""
    eps, own = declared()
    plugins = sorted(set(eps) - own - {STATE})
    return (STATE, *sorted(own - {STATE}), *plugins)


def _unknown(name: str) -> ConfigError:
    return ConfigError(f"unknown perception mode {name!r}; valid modes: {', '.join(perception_modes())}")


def check_mode(name: str) -> str:
    """``name`` if it is a perception mode, else a :class:`ConfigError` naming the valid ones."""
    if name not in perception_modes():
        raise _unknown(name)
    return name


def load_perceiver(name: str) -> Perceiver:
    """The perceiver of mode ``name`` (``state`` has none: a ConfigError, as for unknown names)."""
    eps, own = declared()
    if name == STATE or name not in eps:
        raise _unknown(name)
    ep = eps[name]
    dist = getattr(ep, "dist", None)
    origin = dist.metadata["Name"] if dist is not None else f"{OWN_DIST}'s pyproject.toml" if name in own else "?"
    where = f"perceiver {name!r} ({ep.value}, from {origin})"
    try:
        target: Any = ep.load()
        obj = target() if inspect.isclass(target) or (callable(target) and not hasattr(target, "perceive")) else target
    except Exception as exc:  # noqa: BLE001 - a broken plugin is named, not a traceback three modules later
        raise PluginError(f"{where} failed to load: {type(exc).__name__}: {exc}") from exc
    if not callable(getattr(obj, "perceive", None)):
        raise PluginError(f"{where} is not a Perceiver: it has no perceive(bundle) method")
    return obj
