"""Literals a relation check takes from nowhere: block colours and counts the goal does not say.

Such a check is not blind and does not hold at the start, so the reporter's other gates let it
through, and its verdict is the same for the achieved and the failed state.  The rule is the one a
reader applies: a check may use what the goal says and what it computes from the objects, nothing
else.  Read from the answer's text with :mod:`ast`, without any task knowledge, it is ungrounded
when it has:

* a block colour written as a literal (``blocks(color="orange")``) that the goal uses only to name
  a place ("the orange zone");
* a block colour written as a literal that the goal never says, when the scene has blocks of
  colours the literal does not list (a literal that lists every block colour, such as
  ``["green", "yellow"]`` for the two colours of an alternating stack, picks them all: it is
  ``blocks()`` and guesses nothing) and no zone or bowl has that colour (a place's colour is the
  "matching colour" reading, ``require_inside(blocks(color="brown"), bowl("brown"))``);
* a count written as a literal in ``require_count`` that is not a number of the goal.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterable
from typing import Any

from capmj.agents.lmp.codeprep import named_calls

__all__ = ["goal_numbers", "ungrounded"]

PLACE_NOUNS = ("zone", "zones", "bowl", "bowls", "area", "areas")
"""Nouns after which a colour word names a place, not blocks."""
NUMBER_WORDS = ("zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten", "eleven",
                "twelve")
"""Number words a goal may spell out, by value."""
_NOT_COLOURS = frozenset({"warm", "cool", "big", "bigger", "large", "small", "smaller", "tiny"})


def _strings(node: ast.AST) -> list[str]:
    """The string constants of a literal colour argument (one string, or a list/tuple of them)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value]
    if isinstance(node, (ast.List, ast.Tuple)):
        return [e.value for e in node.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)]
    return []


def _argument(call: ast.Call, position: int, keyword: str) -> ast.AST | None:
    for kw in call.keywords:
        if kw.arg == keyword:
            return kw.value
    return call.args[position] if len(call.args) > position else None


def goal_numbers(goal: str) -> set[int]:
    """The numbers a goal says, in digits or spelled out ("2*2*2" → 2; "two" → 2), with 0 and 1 ("no other
    block", "a block"), which a goal need not spell."""
    words = re.findall(r"[a-z]+|\d+", goal.lower())
    return ({0, 1} | {int(w) for w in words if w.isdigit()}
            | {NUMBER_WORDS.index(w) for w in words if w in NUMBER_WORDS})


def ungrounded(code: str, goal: str, rows: Iterable[dict[str, Any]]) -> str | None:
    """Why ``code`` uses a block colour or a count that the goal does not give (a sentence for the repair
    request), or None.  ``rows``: the scene's records (for the colours its blocks have)."""
    try:
        tree = ast.parse(code)
    except SyntaxError:
        return None  # the sandbox reports it
    words = re.findall(r"[a-z]+", goal.lower())
    rows = list(rows)
    block_colours = {r["color"] for r in rows if r.get("kind") == "block"}
    place_colours = {r["color"] for r in rows if r.get("kind") in ("zone", "bowl")}
    for _, call in named_calls(tree, "blocks"):
        arg = _argument(call, 0, "color")
        colours = _strings(arg) if arg is not None else []
        picked = set(colours)
        for colour in colours:  # in the answer's order: the repair request must not vary between runs
            if colour.lower() in _NOT_COLOURS:
                continue
            said = [i for i, w in enumerate(words) if w == colour.lower()]
            if said and all(i + 1 < len(words) and words[i + 1] in PLACE_NOUNS for i in said):
                noun = words[said[0] + 1]
                return (f'blocks(color="{colour}") picks {colour} blocks, but in the goal "{colour}" names the '
                        f'{colour} {noun}, not the blocks: pick the blocks the goal means (all of them: blocks())')
            if not said and block_colours - picked and colour not in place_colours:
                return (f'blocks(color="{colour}") picks {colour} blocks, but the goal names no colour "{colour}": '
                        "when the goal means a colour chosen by a property (the same colour as a place, the commonest "
                        'colour ...), compute it from the objects, e.g. from [b["color"] for b in blocks()]')
    numbers = goal_numbers(goal)
    for _, call in named_calls(tree, "require_count"):
        n = _argument(call, 2, "n")
        if isinstance(n, ast.Constant) and isinstance(n.value, int) and n.value not in numbers:
            return (f"require_count(..., {n.value}) asks for {n.value} objects, but the goal says no number "
                    f"{n.value}: compute the count from the objects (e.g. with len(...)) or use the goal's numbers")
    return None
