"""Whether a model-written check can tell one scene from another: what it reads and compares.

A check over the scene's records (``prompts/reporter_records.py``) is evidence about the robot's
work only if its verdict depends on what acting changes.  Two kinds of check are blind by their
text, and this module finds both without running anything (the code is read with :mod:`ast`):

* it reads none of the **measured keys** (:data:`MEASURED_KEYS`: ``area``, ``inside``, ``level`` ...,
  the keys acting can change), e.g. ``judge = False`` or a filter on colours alone;
* it compares a key with a **value no record has**, e.g. ``b["inside"] != "zone"`` (the zones'
  names are ``"green zone"`` ...) or ``o["area"] == "left"``: the comparison gives the same answer in
  every scene.  The values a key can have are those of the records of the scenes given, the
  names of the objects that could fill it (a zone's or bowl's for ``inside``, a movable object's
  for ``below`` ...) and the documented words (:data:`WORDS`); so the start scene alone gives
  them, and a repair request that lists them says nothing of the result.

:func:`blind_problem` states the first such problem as a sentence the repair request can quote,
with the values the key really has, so the model can mend the comparison it wrote.  Why this gate
exists: ``docs/judge.md``, "Why each gate exists" (``blind_check``).
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from capmj.agents.report.scene_facts import AREAS
from capmj.agents.report.scene_records import INVENTORY_KEYS, RECORD_KEYS

__all__ = ["MEASURED_KEYS", "WORDS", "blind_problem", "keys_read", "unmatched_comparisons"]

MEASURED_KEYS = tuple(k for k in RECORD_KEYS if k not in INVENTORY_KEYS)
"""The record keys acting can change: a check must read one of them to depend on the scene."""

WORDS: dict[str, tuple[str, ...]] = {
    "area": AREAS, "start_area": AREAS, "rests_on": ("table", "nothing"), "inside": ("",), "inside_color": ("",),
    "kind": ("block", "zone", "bowl", "ball", "fixture"), "size": ("tiny", "small", "big"),
}
"""The values the prompt documents for a key, whether or not a record of this scene has them."""

_SHOWN = 8
"""At most this many of a key's values are listed in a problem (the names are long)."""


def _key_of(node: ast.expr) -> str | None:
    """The record key ``node`` reads: ``x["key"]`` or ``x.get("key", ...)``."""
    if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant) and isinstance(node.slice.value, str):
        return node.slice.value
    if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get" and node.args
            and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)):
        return node.args[0].value
    return None


def keys_read(tree: ast.AST) -> set[str]:
    """The record keys the code reads by name (``x["key"]``, ``x.get("key")``)."""
    return {k for node in ast.walk(tree) if isinstance(node, ast.expr) and (k := _key_of(node)) in RECORD_KEYS}


def _strings(node: ast.expr) -> list[str]:
    """The string constants ``node`` is made of: a constant, or a list/tuple/set of them."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value]
    if isinstance(node, (ast.List, ast.Tuple, ast.Set)):
        return [e.value for e in node.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)]
    return []


def _values(scenes: Iterable[Sequence[Mapping[str, Any]]]) -> dict[str, set[str]]:
    """Every string value each key has, or could have, in the records of ``scenes`` (list values flattened)."""
    out: dict[str, set[str]] = {k: set(WORDS.get(k, ())) for k in RECORD_KEYS}
    for rows in scenes:
        for row in rows:  # what a key could hold in another scene: a container's name, an object's name
            kind = row.get("kind")
            container = kind in ("zone", "bowl")
            keys = ("inside", "inside_color") if container else ("below", "holds")
            for key in keys + (("rests_on",) if kind != "zone" else ()):
                out[key].add(str(row.get("color" if key == "inside_color" else "name")))
            for key, value in row.items():
                for v in value if isinstance(value, list) else [value]:
                    if isinstance(v, str) and key in out:
                        out[key].add(v)
    return out


def unmatched_comparisons(tree: ast.AST, scenes: Iterable[Sequence[Mapping[str, Any]]]) -> list[tuple[str, str]]:
    """``(key, value)`` for each comparison of a key with a string no record of ``scenes`` has for it.

    Compared are ``x["key"] == "v"`` (and ``!=``, ``in``/``not in`` a list of strings, either side).
    ``"v" in x["key"]`` is a test for a part of a string or a member of a list and is left alone."""
    values = _values(scenes)
    found: list[tuple[str, str]] = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Compare):
            continue
        left = node.left
        for op, right in zip(node.ops, node.comparators):
            pairs = [(left, right)] if isinstance(op, (ast.In, ast.NotIn)) else [(left, right), (right, left)]
            if isinstance(op, (ast.Eq, ast.NotEq, ast.In, ast.NotIn)):
                for keyed, other in pairs:
                    key = _key_of(keyed)
                    if key in values and values[key]:
                        found += [(key, v) for v in _strings(other) if v not in values[key]]
            left = right
    return list(dict.fromkeys(found))


def blind_problem(code: str, scenes: Iterable[Sequence[Mapping[str, Any]]]) -> str | None:
    """Why the check ``code`` gives one verdict whatever the scene (a sentence for the repair request), or None."""
    try:
        tree = ast.parse(code)
    except SyntaxError:
        return None  # the sandbox reports it
    if not keys_read(tree) & set(MEASURED_KEYS):
        return (f"it reads none of the measured keys ({', '.join(MEASURED_KEYS)}), so it gives the same verdict "
                f"whatever the robot did: compare them with the goal")
    scenes = list(scenes)
    unmatched = unmatched_comparisons(tree, scenes)
    if not unmatched:
        return None
    key, value = unmatched[0]
    have = sorted(_values(scenes)[key])
    shown = ", ".join(repr(v) for v in have[:_SHOWN]) + (" ..." if len(have) > _SHOWN else "")
    return (f"it compares \"{key}\" with {value!r}, a value no record can have, so that test never changes; "
            f"the values of \"{key}\" here are {shown}")
