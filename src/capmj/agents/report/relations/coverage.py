"""Relations a goal names that a relation check never asks for: the other half of a partial check.

A check that writes one relation of two ("stack all blocks in the orange zone" as
``require_inside`` alone) says "achieved" of every state that keeps the relation it wrote and
breaks the one it left out.  The rule is a reader's, with no task knowledge: a goal that says
"stack" asks for a stack or layers, "structure" or "layer" for layers, "circle" or "ring" for a
circle, "alternat..." for alternating colours, and "in/on/into the ... zone/bowl" for where the
objects must be.  A check that calls none of the matching ``require_*`` misses a relation the goal
names.  The words are the relations' own names in the prompt, not any task's goal.
"""

from __future__ import annotations

import ast
import re

from capmj.agents.lmp.codeprep import named_calls

__all__ = ["COVERAGE", "uncovered"]

PLACED = ("require_inside", "require_outside", "require_count")
"""Checks that say where objects must (not) be; ``require_stack(objs, place)`` does too."""

KEEP = "add one of {checks} to the calls the goal needs (keep the others)"
"""The advice of a repair request for a relation left out."""

COVERAGE: tuple[tuple[str, str, tuple[str, ...], str], ...] = (
    (r"\bstack", "a stack", ("require_stack", "require_layers"), KEEP),
    (r"\b(?:structure|layer)s?\b", "layers (a structure has several blocks in a layer; a tower is one column)",
     ("require_layers",), "write require_layers(objs, [n1, n2, ...]) with the number of blocks in each layer from the "
                          "table up, instead of require_stack"),
    (r"\b(?:circle|ring)s?\b", "a circle", ("require_circle",), KEEP),
    (r"\balternat", "alternating colours", ("require_alternating",), KEEP),
    (r"\b(?:in|on|into|onto)\s+(?:the|a|an|each|every)\s+(?:[a-z]+\s+){0,2}?(?:zone|bowl)s?\b",
     "where the objects must be (a zone or bowl)", PLACED, KEEP),
)
"""(goal pattern, what it asks for, the checks any one of which asks for it, the advice).  "structure" and
"layer" are the prompt's own words for ``require_layers``, so their advice asks for layers instead of a tower."""


def _asked(tree: ast.AST) -> set[str]:
    """The ``require_*`` names the code calls; ``require_stack`` with a place counts as placing too."""
    names: set[str] = set()
    for name, call in named_calls(tree):
        names.add(name)
        if name == "require_stack" and (len(call.args) > 1 or any(k.arg == "place" for k in call.keywords)):
            names.add(PLACED[0])
    return names


def uncovered(code: str, goal: str) -> str | None:
    """Which relation the goal names and ``code`` never asks for (a sentence for the repair request), or None."""
    try:
        tree = ast.parse(code)
    except SyntaxError:
        return None  # the sandbox reports it
    asked, text = _asked(tree), goal.lower()
    for pattern, relation, checks, advice in COVERAGE:
        found = re.search(pattern, text)
        if found and not asked & set(checks):
            return (f'the goal says "{found.group(0)}", but no call asks for {relation}: '
                    + advice.format(checks=", ".join(checks)))
    return None
