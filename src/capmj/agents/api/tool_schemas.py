"""The planner API functions as OpenAI-format tools, generated from the functions themselves.

One source: each tool's name is the :class:`~capmj.agents.api.plan_functions.PlanFunctions`
method's, its description the method's docstring, its parameters the method's signature (names,
defaults: a parameter without a default is required) and their JSON Schema types the method's
annotations.  So what ``--policy tools`` offers cannot drift from what plan code calls and the
docstrings promise.

:data:`TOOL_FUNCTIONS` are the functions offered: the API that capmj's planner prompt documents
(``prompts/planner.py`` imports exactly these; a test holds the two equal), not the CapRavens names
kept for ported code nor the helper LMPs, which take a question, not data.
"""

from __future__ import annotations

import functools
import inspect
import types
import typing
from collections.abc import Callable
from typing import Any

import numpy as np

from capmj.agents.api.plan_functions import API_FUNCTIONS, PlanFunctions

__all__ = ["TOOL_FUNCTIONS", "function_schema", "json_schema", "tool_schemas"]

TOOL_FUNCTIONS: tuple[str, ...] = (
    "get_obj_names", "get_obj_pos", "get_obj_rot", "get_bbox", "get_color", "get_obj_positions_np",
    "is_target_occupied", "get_random_free_pos", "put_first_on_second", "stack_objects_in_order", "denormalize",
    "get_corner_name", "get_side_name", "say",
)
"""The planner API functions offered as tools, in the order the planner prompt imports them."""

_SCALARS: dict[Any, dict[str, Any]] = {str: {"type": "string"}, int: {"type": "integer"},
                                        float: {"type": "number"}, bool: {"type": "boolean"}}


def json_schema(annotation: Any) -> dict[str, Any]:
    """The JSON Schema of a type annotation: str, int, float, bool, None, ``list[X]``, ``tuple[X, ...]``
    and fixed tuples (arrays), ``dict`` (object), unions (``anyOf``, one member kept as it is), a numpy
    array (nested arrays of numbers); ``Any`` is ``{}`` (any value).  Another type raises TypeError."""
    if annotation in _SCALARS:
        return dict(_SCALARS[annotation])
    if annotation is None or annotation is type(None):
        return {"type": "null"}
    if annotation is Any:
        return {}
    if annotation is np.ndarray:
        return {"type": "array", "items": {"anyOf": [{"type": "number"}, {"type": "array"}]}}
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin in (typing.Union, types.UnionType):
        members: list[dict[str, Any]] = []
        for a in args:
            schema = json_schema(a)
            if schema not in members:
                members.append(schema)
        return members[0] if len(members) == 1 else {"anyOf": members}
    if origin is list or (origin is tuple and len(args) == 2 and args[1] is Ellipsis):
        return {"type": "array", "items": json_schema(args[0])}
    if origin is tuple:
        items = [json_schema(a) for a in args]
        same = all(i == items[0] for i in items)
        return {"type": "array", "items": items[0] if same else {"anyOf": items},
                "minItems": len(items), "maxItems": len(items)}
    if annotation is dict or origin is dict:
        return {"type": "object"}
    raise TypeError(f"no JSON Schema for the annotation {annotation!r}")


def _description(fn: Callable[..., Any]) -> str:
    """The docstring as one text: paragraphs kept, lines of a paragraph joined."""
    doc = inspect.getdoc(fn) or ""
    paragraphs = [" ".join(p.split()) for p in doc.split("\n\n")]
    return "\n".join(p for p in paragraphs if p)


def function_schema(name: str, fn: Callable[..., Any] | None = None) -> dict[str, Any]:
    """The OpenAI tool of one planner API function (``fn``: the function, default the
    :class:`PlanFunctions` method of that name): description from its docstring, parameters from
    its signature and annotations (an unannotated parameter takes any value)."""
    fn = fn if fn is not None else getattr(PlanFunctions, name)
    hints = typing.get_type_hints(fn)
    properties: dict[str, Any] = {}
    required: list[str] = []
    for p in inspect.signature(fn).parameters.values():
        if p.name == "self" or p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            continue
        schema = json_schema(hints.get(p.name, Any))
        if p.default is inspect.Parameter.empty:
            required.append(p.name)
        else:
            schema["default"] = p.default
        properties[p.name] = schema
    parameters: dict[str, Any] = {"type": "object", "properties": properties, "required": required}
    return {"type": "function", "function": {"name": name, "description": _description(fn), "parameters": parameters}}


@functools.cache
def _schemas() -> tuple[dict[str, Any], ...]:
    missing = [n for n in TOOL_FUNCTIONS if n not in API_FUNCTIONS]
    if missing:
        raise TypeError(f"tools {missing} are not planner API functions")
    return tuple(function_schema(n) for n in TOOL_FUNCTIONS)


def tool_schemas() -> list[dict[str, Any]]:
    """The tools of :data:`TOOL_FUNCTIONS`, in that order (fresh copies: a caller may change them)."""
    import copy

    return copy.deepcopy(list(_schemas()))
