"""What a relation check picks: the objects and places it names, over one scene's records.

The ``relations`` reporter's code says *which* objects a relation is about with a few selectors
(``blocks(color="red")``, ``zone("green")``, ``bowls()`` ...) and passes their results, or names,
to the checks of :mod:`capmj.agents.report.relations.checks`.  This module is where those words become
records.  It is forgiving where a small model's slip has one meaning (``blocks(color="big")`` is a
size, ``b.color`` reads the key, ``zone("zone")`` and a zone colour nothing in the scene has are
the only zone) and strict everywhere else: anything it cannot read raises
:class:`~capmj.errors.CheckArgumentError` naming the valid choices, which the reporter's repair
request quotes.  A literal pick the goal does not give (:func:`ungrounded`) is the reporter's
``ungrounded_literal`` gate.  A pick that finds no block is noted (:attr:`Picks.empty_picks`): a relation over nothing
always holds, and the holds-at-start repair request names what exists instead.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from capmj.agents.report.scene import AREAS
from capmj.agents.report.verdict import Answer
from capmj.errors import CheckArgumentError
from capmj.sim.palette import COOL, WARM

__all__ = ["SELECTORS", "SIZE_WORDS", "Picks", "Record", "goal_numbers", "short", "ungrounded"]

Record = dict[str, Any]

SIZE_WORDS = {"big": "big", "bigger": "big", "large": "big", "small": "small", "smaller": "small", "tiny": "tiny"}
"""What ``blocks(size=...)`` accepts, and the record size each word means."""
SIDES = {"left": (1, -1.0), "right": (1, 1.0), "front": (0, 1.0), "rear": (0, -1.0)}
"""``blocks_beside`` sides: (axis, sign) of the start-centre difference (left = y−, front = x+, as the area words)."""
PLACE_KINDS = ("zone", "bowl")
"""The kinds of object a place can be (besides an area word)."""
SELECTORS = ("blocks", "other_blocks", "blocks_beside", "zone", "bowl", "ball", "zones", "bowls")
"""The functions that pick objects and places, in the order the prompt documents them."""


class _Record(dict):  # type: ignore[type-arg]
    """A record whose keys read as attributes too (``b.color``): small models write both."""

    def __getattr__(self, key: str) -> Any:
        try:
            return self[key]
        except KeyError:
            raise AttributeError(f"an object has no key {key!r}; its keys are {list(self)}") from None


def short(name: str) -> str:
    """An object's name as a sentence says it."""
    return name.removeprefix("movable ")


class Picks:
    """The selectors of one scene, and the reads of objects and places the checks share.

    ``rows``: the scene's records (copied: a check may mutate what it is given); ``start_rows``:
    the records of the scene the robot started from (for ``blocks_beside`` and ``require_unmoved``;
    the scene itself when None)."""

    def __init__(self, rows: Sequence[Record], start_rows: Sequence[Record] | None = None) -> None:
        self.rows: list[Record] = [_Record(r) for r in rows]
        self.by_name = {r["name"]: r for r in self.rows}
        self.start = {r["name"]: r for r in (start_rows if start_rows is not None else self.rows)}
        self.movable = [r for r in self.rows if r["kind"] not in (*PLACE_KINDS, "fixture")]
        self.empty_picks: list[str] = []
        """``blocks(...)`` calls that picked no block, as sentences (a relation over nothing always holds)."""

    def bindings(self) -> dict[str, Any]:
        """The names :data:`SELECTORS` (and ``objects``) a check may use."""
        return {
            "objects": self.rows,
            "blocks": self.blocks, "other_blocks": self.other_blocks, "blocks_beside": self.blocks_beside,
            "zone": lambda color=None: self.the("zone", color), "bowl": lambda color=None: self.the("bowl", color),
            "ball": lambda color=None: self.the("ball", color),
            "zones": lambda: self.of_kind("zone"), "bowls": lambda: self.of_kind("bowl"),
        }

    # -- reads the checks share -------------------------------------------------------------------

    def objs(self, value: Any, what: str = "objects") -> list[Record]:
        """The records ``value`` means: one record or name, or a list of them."""
        if value is None:
            raise CheckArgumentError(f"{what} is None: pick objects with blocks(...) or a list of records")
        items = value if isinstance(value, (list, tuple, set, frozenset)) else [value]
        out: list[Record] = []
        for item in items:
            name = item.get("name") if isinstance(item, dict) else item
            if not isinstance(name, str) or name not in self.by_name:
                raise CheckArgumentError(f"{str(item)[:60]!r} is not an object of this scene: pass records "
                                f"from blocks(...) or objects, or their full names")
            out.append(self.by_name[name])
        return out

    def places(self, value: Any) -> tuple[str, ...]:
        """Zone/bowl names or area words; a list of places means any one of them."""
        if isinstance(value, (list, tuple)) and value:
            return tuple(self._place(v) for v in value)
        return (self._place(value),)

    def _place(self, value: Any) -> str:
        if isinstance(value, dict):
            value = value.get("name")
        if isinstance(value, str):
            if value in AREAS:
                return value
            if value in self.by_name and self.by_name[value]["kind"] in PLACE_KINDS:
                return value
            found = [r["name"] for r in self.rows if r["kind"] in PLACE_KINDS
                     and value in (r["color"], f"{r['color']} {r['kind']}", r["kind"])]
            if len(found) == 1:
                return found[0]
        places = [r["name"] for r in self.rows if r["kind"] in PLACE_KINDS]
        raise CheckArgumentError(f"{str(value)[:60]!r} is not a place: use zone(color), bowl(color), zones(), "
                        f"bowls(), one of {places} or an area {list(AREAS)}")

    @staticmethod
    def is_in(r: Record, where: tuple[str, ...]) -> bool:
        return any(r["area"] == p if p in AREAS else r["inside"] == p for p in where)

    @staticmethod
    def said(where: tuple[str, ...]) -> str:
        return where[0] if len(where) == 1 else "any of " + ", ".join(where)

    # -- the selectors ------------------------------------------------------------------------------

    def of_kind(self, kind: str) -> list[Record]:
        return [r for r in self.rows if r["kind"] == kind]

    def the(self, kind: str, color: Any = None) -> Record:
        """The one object of ``kind`` (of ``color`` when given)."""
        if isinstance(color, dict):
            color = color.get("color")
        if color in (kind, f"{kind}s", f"the {kind}"):  # zone("zone"): the kind word, not a colour
            color = None
        every = self.of_kind(kind)
        found = [r for r in every if color in (None, r["color"])]
        if not found and len(every) == 1 and color not in {r["color"] for r in self.rows}:
            # zone("purple") with one yellow zone and nothing purple: a colour copied from an example, where
            # the goal says "the zone" (a goal cannot name a place the scene lacks); a colour some object has
            # may be a loop over colours, and stays an error
            return every[0]
        if len(found) != 1:
            colors = sorted({r["color"] for r in every})
            which = f"{color} {kind}" if color is not None else f"single {kind} (there are {len(found)})"
            hint = (f": the only {kind} is the {colors[0]} one, {kind}() picks it" if len(colors) == 1 else
                    f": loop over {kind}s() to visit only those that exist" if kind != "ball" else "")
            raise CheckArgumentError(f"there is no {which}; the {kind}s here are {colors}{hint}")
        return found[0]

    def blocks(self, color: Any = None, size: str | None = None, start_area: str | None = None) -> list[Record]:
        words = [color] if isinstance(color, str) else list(color or [])
        if size is None and len(words) == 1 and words[0] in SIZE_WORDS:  # blocks(color="big"): a size, not a colour
            size, words, color = words[0], [], None
        colors = None if color is None else {c for w in words for c in (WARM if w == "warm" else COOL if w == "cool"
                                                                        else [w])}
        if size is not None and size not in SIZE_WORDS:
            raise CheckArgumentError(f"size {size!r}: valid: {', '.join(SIZE_WORDS)}")
        if start_area is not None and start_area not in AREAS:
            raise CheckArgumentError(f"start_area {start_area!r}: valid: {', '.join(AREAS)}")
        every = [r for r in self.movable if r["kind"] == "block"]
        found = [r for r in every if (colors is None or r["color"] in colors)
                 and (size is None or r["size"] == SIZE_WORDS[size]) and (start_area is None or r["start_area"] == start_area)]
        if not found and every and (colors is not None or size is not None or start_area is not None):
            # legitimate in a loop over bowls (a distractor's colour), but also a place's colour read as the
            # blocks' (a literal one is caught first by the ungrounded gate): kept for the repair request of a
            # check that tests nothing
            self.empty_picks.append(
                f"blocks(color={color!r}, size={size!r}, start_area={start_area!r}) picks no block: the blocks here "
                f"have the colours {sorted({r['color'] for r in every})}, the sizes {sorted({r['size'] for r in every})} "
                f"and started in {sorted({r['start_area'] for r in every})}")
        return found

    def other_blocks(self, objs: Any) -> list[Record]:
        names = {r["name"] for r in self.objs(objs)}
        return [r for r in self.blocks() if r["name"] not in names]

    def blocks_beside(self, block: Any, side: str, more_than: float = 0.0) -> list[Record]:
        ref = self.objs(block, "block")[0]
        if side not in SIDES:
            raise CheckArgumentError(f"side {side!r}: valid: {', '.join(SIDES)}")
        axis, sign = SIDES[side]
        return [r for r in self.blocks() if r["name"] != ref["name"]
                and sign * (self.start[r["name"]]["centre"][axis] - self.start[ref["name"]]["centre"][axis]) > more_than]


# ------------------------------------------------------------------------------------------------
# literals a check picks from nowhere: block colours and counts the goal does not say
# ------------------------------------------------------------------------------------------------
PLACE_NOUNS = ("zone", "zones", "bowl", "bowls", "area", "areas")
"""Nouns after which a colour word names a place, not blocks."""
NUMBER_WORDS = ("zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten", "eleven",
                "twelve")
"""Number words a goal may spell out, by value."""
_NOT_COLOURS = frozenset({"warm", "cool", "big", "bigger", "large", "small", "smaller", "tiny"})


def goal_numbers(goal: str) -> set[int]:
    """The numbers a goal says, in digits or spelled out ("2*2*2" → 2; "two" → 2), with 0 and 1 ("no other
    block", "a block"), which a goal need not spell."""
    words = re.findall(r"[a-z]+|\d+", goal.lower())
    return ({0, 1} | {int(w) for w in words if w.isdigit()}
            | {NUMBER_WORDS.index(w) for w in words if w in NUMBER_WORDS})


def _strings(node: ast.AST | None) -> list[str]:
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


def ungrounded(code: Answer | str, goal: str, rows: Iterable[Mapping[str, Any]]) -> str | None:
    """Why the check uses a literal the goal does not give (a sentence for the repair request), or None.

    A check may use what the goal says and what it computes from the objects, nothing else: a block
    colour the goal uses only to name a place ("the orange zone"); a block colour the goal never
    says, when the scene has blocks of colours the literal does not list (one that lists every block
    colour picks them all) and no zone or bowl has it (a place's colour is the "matching colour"
    reading); a count in ``require_count`` that is not a number of the goal.  ``rows``: the scene's
    records (for the colours its blocks have)."""
    answer = code if isinstance(code, Answer) else Answer.read(code)
    if answer.tree is None:
        return None  # the sandbox reports it
    words = re.findall(r"[a-z]+", goal.lower())
    rows = list(rows)
    block_colours = {r["color"] for r in rows if r.get("kind") == "block"}
    place_colours = {r["color"] for r in rows if r.get("kind") in ("zone", "bowl")}
    for _, call in answer.calls("blocks"):
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
    for _, call in answer.calls("require_count"):
        n = _argument(call, 2, "n")
        if isinstance(n, ast.Constant) and isinstance(n.value, int) and n.value not in numbers:
            return (f"require_count(..., {n.value}) asks for {n.value} objects, but the goal says no number "
                    f"{n.value}: compute the count from the objects (e.g. with len(...)) or use the goal's numbers")
    return None
