"""What generated task code may reference: names, not modules (issue #25).

Allowing a *module* lets everything that module imported come along as an attribute
(``registry.os``, ``typing.sys``, ``numpy.f2py.os``).  So the allow-list names every module a
task may import together with the members it may use from it; an attribute of a module object
outside its list is rejected by :mod:`capmj.confine.names`.  The same table renders the
"Imports allowed" line and the API reference of ``prompts/generator/task_api.txt`` (the writing turn)
(:func:`allowed_imports_text`, :func:`capmj.generate.library.api_reference`), so what the model
is told and what the check accepts are one fact.

Nothing here imports a listed module at import time: the members of ``capmj.tasks.predicates``
are its ``__all__`` (its documented surface), read when first needed.
"""

from __future__ import annotations

import importlib
import itertools
import math
from functools import cache

_NUMPY = (
    "abs", "absolute", "all", "allclose", "amax", "amin", "any", "arange", "arccos", "arcsin", "arctan",
    "arctan2", "argmax", "argmin", "argsort", "around", "array", "array_equal", "asarray", "bool_", "ceil",
    "clip", "column_stack", "concatenate", "cos", "count_nonzero", "cross", "cumsum", "deg2rad", "degrees",
    "diff", "dot", "e", "empty", "exp", "flatnonzero", "float32", "float64", "floor", "full", "hstack", "hypot",
    "inf", "int32", "int64", "interp", "intp", "isclose", "isfinite", "isnan", "linspace", "log", "max",
    "maximum", "mean", "median", "meshgrid", "min", "minimum", "mod", "nan", "ndarray", "newaxis", "nonzero",
    "ones", "ones_like", "outer", "pi", "prod", "rad2deg", "radians", "ravel", "repeat", "reshape", "rint",
    "round", "sign", "sin", "sort", "sqrt", "square", "stack", "std", "sum", "tan", "tile", "transpose",
    "unique", "unwrap", "var", "vstack", "where", "zeros", "zeros_like",
)
"""Array construction and arithmetic a scene sampler or judge needs; no I/O, no ``ctypeslib``,
no global random state (``numpy.random`` offers only the ``Generator`` type for annotations)."""

_TYPING = ("Any", "Callable", "ClassVar", "Final", "Iterable", "Iterator", "Literal", "Mapping", "Optional",
           "Sequence", "TYPE_CHECKING", "Tuple", "Union")
"""Annotations only: ``get_type_hints``/``ForwardRef`` evaluate strings, so they are left out."""

_CAPMJ: dict[str, tuple[str, ...]] = {
    "capmj.tasks.protocol": ("Scene", "Target", "OracleGoal", "Verdict", "Resample"),
    "capmj.tasks.spawn": ("Spawner", "pick_colors", "pick_color", "DEFAULT_COLORS", "WARM_COLORS", "COOL_COLORS",
                          "Bounds", "SPAWN_BOUNDS", "centre_bounds", "free_positions"),
    "capmj.tasks.predicates": (),  # its __all__, see members()
    "capmj.sim.state": ("Pose", "SceneState"),
    "capmj.sim.objects": ("ObjectSpec", "BLOCK_SIZES", "ZONE_SIZE", "BOWL_HEIGHT", "BOWL_FLOOR",
                          "BOWL_INNER_RADIUS", "KINDS", "FIXED_KINDS", "resting_z"),
}
"""capmj's task API, in the order the prompt documents it."""

_STATIC: dict[str, tuple[str, ...]] = {
    "__future__": ("annotations",),
    "math": tuple(n for n in dir(math) if not n.startswith("_")),  # pure functions and constants only
    "itertools": tuple(n for n in dir(itertools) if not n.startswith("_")),  # pure iterator builders
    "typing": _TYPING,
    "dataclasses": ("dataclass", "field", "replace", "asdict", "astuple", "fields", "FrozenInstanceError"),
    "numpy": _NUMPY,
    "numpy.linalg": ("norm", "det", "inv", "solve"),
    "numpy.random": ("Generator",),
    **_CAPMJ,
}

IMPORTABLE: tuple[str, ...] = tuple(_STATIC)
"""Every module a task may import (exactly these; ``numpy.f2py`` is not ``numpy``)."""

CAPMJ_API: tuple[str, ...] = tuple(_CAPMJ)
"""The capmj modules of the task API, as :func:`capmj.generate.library.api_reference` documents them."""


@cache
def _predicates() -> tuple[str, ...]:
    module = importlib.import_module("capmj.tasks.predicates")
    return tuple(module.__all__)


def members(module: str) -> frozenset[str]:
    """The names a task may use from ``module`` (empty for a module outside the list)."""
    if module == "capmj.tasks.predicates":
        return frozenset(_predicates())
    return frozenset(_STATIC.get(module, ()))


def ordered_members(module: str) -> tuple[str, ...]:
    """:func:`members` in the documented order (for the prompt)."""
    return _predicates() if module == "capmj.tasks.predicates" else _STATIC.get(module, ())


@cache
def transit_modules() -> frozenset[str]:
    """Modules a dotted path may pass through on its way to an allowed module (``capmj``,
    ``capmj.tasks``), besides the importable ones.  They offer no members of their own."""
    out: set[str] = set()
    for m in IMPORTABLE:
        parts = m.split(".")
        out.update(".".join(parts[:i]) for i in range(1, len(parts)))
    return frozenset(out - set(IMPORTABLE))


def is_module(path: str) -> bool:
    """``path`` names an importable or a transit module."""
    return path in _STATIC or path in transit_modules()


def allowed_imports_text() -> str:
    """The prompt's "Imports allowed" block: each module with the names it offers."""
    lines = []
    for m in IMPORTABLE:
        names = ordered_members(m)
        if m.startswith("capmj."):
            lines.append(f"  {m}: the names in the reference below")
        elif m in ("math", "itertools"):
            lines.append(f"  {m}: every public function and constant")
        else:
            lines.append(f"  {m}: {', '.join(names)}")
    return "\n".join(lines)


__all__ = ["CAPMJ_API", "IMPORTABLE", "allowed_imports_text", "is_module", "members", "ordered_members",
           "transit_modules"]
