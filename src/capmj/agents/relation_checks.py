"""Pre-bound relation checks over a measured scene: what the ``relations`` reporter's code calls.

Why: with the shared 1.5B model, checks written from scratch over the scene records
(``records``/``goalcheck``) were wrong in the plumbing more often than in the goal: a name used
before it was set, ``judge`` set to a constant, a key compared with a word no record has, a level
list compared with the wrong range.  86 of 99 judge episodes got the same verdict for the achieved
and the failed state.  Here the model only says *which* relations the goal asks for, as calls such
as ``require_inside(blocks(color="red"), zone("green"))``; each call measures its relation on the
records and, when it fails, records a sentence and the names of the objects that break it.  The
verdict is "achieved" exactly when no call failed, and ``wrong`` is the union of the names, so a
"not achieved" always names objects.

The relations are generic to tabletop goals (inside, outside, one stack, layers, on the table,
unmoved, a circle, a row, alternating colours, a count, distinct colours); each is measured from
the records of :mod:`capmj.agents.scene_records` with the tasks' own tolerances
(:mod:`capmj.tasks.predicates`), as the records themselves are.  No call knows any task.

:func:`relation_env` builds the names a check may use for one scene; :class:`Failures` collects
what failed.  Calls are forgiving in what they take (a record, a list of records, a name, a colour
word where a zone or bowl is meant) because a small model mixes them; anything else raises
:class:`~capmj.errors.PlanError` with the valid choices, which the reporter's repair request quotes.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from capmj.agents.scene_facts import AREAS
from capmj.errors import PlanError
from capmj.sim.palette import COOL, WARM
from capmj.tasks.predicates import CENTRE_TOL, CIRCLE_TOL, ROW_LINE_TOL, fit_circle
from capmj.tasks.predicates.tolerances import MOVE_TOL

__all__ = ["CHECKS", "NAMES", "SELECTORS", "Failures", "relation_env"]

Record = dict[str, Any]

SIZE_WORDS = {"big": "big", "bigger": "big", "large": "big", "small": "small", "smaller": "small", "tiny": "tiny"}
"""What ``blocks(size=...)`` accepts, and the record size each word means."""
SIDES = {"left": (1, -1.0), "right": (1, 1.0), "front": (0, 1.0), "rear": (0, -1.0)}
"""``blocks_beside`` sides: (axis, sign) of the start-centre difference (left = y−, front = x+, as the area words)."""

CHECKS = ("require_inside", "require_outside", "require_stack", "require_layers", "require_on_table",
          "require_unmoved", "require_circle", "require_row", "require_alternating", "require_count",
          "require_different_colors")
"""The relation checks, in the order the prompt documents them."""
SELECTORS = ("blocks", "other_blocks", "blocks_beside", "zone", "bowl", "ball", "zones", "bowls")
"""The functions that pick objects and places."""
NAMES = ("objects", *SELECTORS, *CHECKS)
"""Every name :func:`relation_env` binds: what a check may use besides Python's builtins."""


class _Record(dict):  # type: ignore[type-arg]
    """A record whose keys read as attributes too (``b.color``): small models write both."""

    def __getattr__(self, key: str) -> Any:
        try:
            return self[key]
        except KeyError:
            raise AttributeError(f"an object has no key {key!r}; its keys are {list(self)}") from None


@dataclass
class Failures:
    """The relations that failed in one run of a check: a sentence and the objects each blames."""

    items: list[tuple[str, tuple[str, ...]]] = field(default_factory=list)
    calls: int = 0
    """How many ``require_*`` calls ran (a check that makes none tests nothing)."""

    empty_picks: list[str] = field(default_factory=list)
    """``blocks(...)`` calls that picked no block, as sentences (a relation over nothing always holds)."""
    demands: list[tuple[str, frozenset[str], Any]] = field(default_factory=list)
    """What each call asked for, ``(relation, objects, detail)``: read by :meth:`impossible`."""

    def add(self, sentence: str, names: Sequence[str]) -> None:
        self.items.append((sentence, tuple(names)))

    def impossible(self) -> str | None:
        """Why no scene could pass every call (a sentence for the repair request), or None.

        The mirror image of a check that holds at the start: one that no arrangement satisfies
        says "not achieved" of every state, and names objects, so the careful loop would act on it.
        Found without any task knowledge: a count above the objects counted, layers that do not add
        up, an object required in two different zones/bowls or both in and out of one, two objects
        of one required tower also required on the table, a tower required to be layered."""
        inside: dict[str, list[frozenset[str]]] = {}
        outside: dict[str, list[frozenset[str]]] = {}
        stacks, tables, layers = [], [], []
        for relation, names, detail in self.demands:
            if relation == "count" and not 0 <= detail <= len(names):
                return f"it requires {detail} of {len(names)} objects in a place"
            if relation == "layers" and (sum(detail) != len(names) or min(detail, default=0) < 1):
                return f"it requires layers of {list(detail)} of {len(names)} objects"
            for name in names:
                {"inside": inside, "outside": outside}.get(relation, {}).setdefault(name, []).append(detail)
            if relation == "stack" and len(names) > 1:
                stacks.append(names)
            tables += [names] if relation == "table" else []
            layers += [(names, detail)] if relation == "layers" else []
        for name, places in inside.items():
            if any(p <= q for p in places for q in outside.get(name, [])):
                return f"it requires {_short(name)} both in and out of the same place"
            containers = [p for p in places if not p & set(AREAS)]
            if any(not p & q for p in containers for q in containers):
                return f"it requires {_short(name)} in two different places at once"
        for tower in stacks:
            if any(len(tower & t) > 1 for t in tables):
                return "it requires the same objects in one tower and all on the table"
            if any(tower == group and max(counts) > 1 for group, counts in layers):
                return ("it requires the same objects in one tower and in layers of several: a tower is a single column; "
                        "a structure with several blocks in a layer is require_layers alone")
        return None

    @property
    def wrong(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(n for _, ns in self.items for n in ns))

    @property
    def reason(self) -> str:
        return "; ".join(s for s, _ in self.items) if self.items else "every required relation holds"


def _short(name: str) -> str:
    return name.removeprefix("movable ")


def relation_env(rows: Sequence[Record], start_rows: Sequence[Record] | None = None
                 ) -> tuple[dict[str, Any], Failures]:
    """The names a check may use over the scene ``rows`` (records), and the :class:`Failures` its calls fill.

    ``start_rows``: the records of the scene the robot started from (for ``require_unmoved``; the
    scene itself when None)."""
    rows = [_Record(r) for r in rows]  # fresh: the check may mutate what it is given
    by_name = {r["name"]: r for r in rows}
    start = {r["name"]: r for r in (start_rows if start_rows is not None else rows)}
    movable = [r for r in rows if r["kind"] not in ("zone", "bowl", "fixture")]
    failures = Failures()

    def objs_of(value: Any, what: str = "objects") -> list[Record]:
        if value is None:
            raise PlanError(f"ValueError: {what} is None: pick objects with blocks(...) or a list of records")
        items = value if isinstance(value, (list, tuple, set, frozenset)) else [value]
        out: list[Record] = []
        for item in items:
            name = item.get("name") if isinstance(item, dict) else item
            if not isinstance(name, str) or name not in by_name:
                raise PlanError(f"ValueError: {str(item)[:60]!r} is not an object of this scene: pass records "
                                f"from blocks(...) or objects, or their full names")
            out.append(by_name[name])
        return out

    def place_one(value: Any) -> str:
        if isinstance(value, dict):
            value = value.get("name")
        if isinstance(value, str):
            if value in AREAS:
                return value
            if value in by_name and by_name[value]["kind"] in ("zone", "bowl"):
                return value
            found = [r["name"] for r in rows if r["kind"] in ("zone", "bowl")
                     and value in (r["color"], f"{r['color']} {r['kind']}", r["kind"])]
            if len(found) == 1:
                return found[0]
        places = [r["name"] for r in rows if r["kind"] in ("zone", "bowl")]
        raise PlanError(f"ValueError: {str(value)[:60]!r} is not a place: use zone(color), bowl(color), zones(), "
                        f"bowls(), one of {places} or an area {list(AREAS)}")

    def place_of(value: Any) -> tuple[str, ...]:
        """Zone/bowl names or area words; a list of places means any one of them."""
        if isinstance(value, (list, tuple)) and value:
            return tuple(place_one(v) for v in value)
        return (place_one(value),)

    def is_in(r: Record, where: tuple[str, ...]) -> bool:
        return any(r["area"] == p if p in AREAS else r["inside"] == p for p in where)

    def said(where: tuple[str, ...]) -> str:
        return where[0] if len(where) == 1 else "any of " + ", ".join(where)

    def the(kind: str, color: Any = None) -> Record:
        """The one object of ``kind`` (of ``color`` when given)."""
        if isinstance(color, dict):
            color = color.get("color")
        if color in (kind, f"{kind}s", f"the {kind}"):  # zone("zone"): the kind word, not a colour
            color = None
        found = [r for r in rows if r["kind"] == kind and color in (None, r["color"])]
        only = [r for r in rows if r["kind"] == kind]
        if not found and len(only) == 1 and color not in {r["color"] for r in rows}:
            # zone("purple") with one yellow zone and nothing purple: a colour copied from an example, where
            # the goal says "the zone" (a goal cannot name a place the scene lacks); a colour some object has
            # may be a loop over colours, and stays an error
            return only[0]
        if len(found) != 1:
            colors = sorted({r["color"] for r in rows if r["kind"] == kind})
            which = f"{color} {kind}" if color is not None else f"single {kind} (there are {len(found)})"
            hint = (f": the only {kind} is the {colors[0]} one, {kind}() picks it" if len(colors) == 1 else
                    f": loop over {kind}s() to visit only those that exist" if kind != "ball" else "")
            raise PlanError(f"ValueError: there is no {which}; the {kind}s here are {colors}{hint}")
        return found[0]

    def blocks_beside(block: Any, side: str, more_than: float = 0.0) -> list[Record]:
        ref = objs_of(block, "block")[0]
        if side not in SIDES:
            raise PlanError(f"ValueError: side {side!r}: valid: {', '.join(SIDES)}")
        axis, sign = SIDES[side]
        return [r for r in blocks() if r["name"] != ref["name"]
                and sign * (start[r["name"]]["centre"][axis] - start[ref["name"]]["centre"][axis]) > more_than]

    def blocks(color: Any = None, size: str | None = None, start_area: str | None = None) -> list[Record]:
        words = [color] if isinstance(color, str) else list(color or [])
        if size is None and len(words) == 1 and words[0] in SIZE_WORDS:  # blocks(color="big"): a size, not a colour
            size, words, color = words[0], [], None
        colors = None if color is None else {c for w in words for c in (WARM if w == "warm" else COOL if w == "cool"
                                                                        else [w])}
        if size is not None and size not in SIZE_WORDS:
            raise PlanError(f"ValueError: size {size!r}: valid: {', '.join(SIZE_WORDS)}")
        if start_area is not None and start_area not in AREAS:
            raise PlanError(f"ValueError: start_area {start_area!r}: valid: {', '.join(AREAS)}")
        every = [r for r in movable if r["kind"] == "block"]
        found = [r for r in every if (colors is None or r["color"] in colors)
                 and (size is None or r["size"] == SIZE_WORDS[size]) and (start_area is None or r["start_area"] == start_area)]
        if not found and every and (colors is not None or size is not None or start_area is not None):
            # legitimate in a loop over bowls (a distractor's colour), but also a place's colour read as the
            # blocks' (a literal one is caught first by relation_grounding): kept for the repair request of a
            # check that tests nothing
            failures.empty_picks.append(
                f"blocks(color={color!r}, size={size!r}, start_area={start_area!r}) picks no block: the blocks here "
                f"have the colours {sorted({r['color'] for r in every})}, the sizes {sorted({r['size'] for r in every})} "
                f"and started in {sorted({r['start_area'] for r in every})}")
        return found

    def other_blocks(objs: Any) -> list[Record]:
        names = {r["name"] for r in objs_of(objs)}
        return [r for r in blocks() if r["name"] not in names]

    def checked(name: str, fn: Callable[..., None]) -> Callable[..., None]:
        def run(*args: Any, **kwargs: Any) -> None:
            failures.calls += 1
            fn(*args, **kwargs)
        run.__name__ = name
        return run

    def names_of(group: Sequence[Record]) -> frozenset[str]:
        return frozenset(r["name"] for r in group)

    def require_inside(objs: Any, place: Any) -> None:
        where, group = place_of(place), objs_of(objs)
        failures.demands.append(("inside", names_of(group), frozenset(where)))
        bad = [r["name"] for r in group if not is_in(r, where)]
        if bad:
            failures.add(f"not in the {said(where)}: {', '.join(map(_short, bad))}", bad)

    def require_outside(objs: Any, place: Any) -> None:
        where, group = place_of(place), objs_of(objs)
        failures.demands.append(("outside", names_of(group), frozenset(where)))
        bad = [r["name"] for r in group if is_in(r, where)]
        if bad:
            failures.add(f"must not be in the {said(where)}: {', '.join(map(_short, bad))}", bad)

    def require_stack(objs: Any, place: Any = None) -> None:
        group = objs_of(objs)
        if place is not None:
            require_inside(group, place)
        names = names_of(group)
        failures.demands.append(("stack", names, None))
        bottom = [r for r in group if r["level"] == 1]
        tower = bottom[:1]
        while tower:
            above = [r for r in group if r["rests_on"] == tower[-1]["name"] and r["name"] not in
                     {t["name"] for t in tower}]
            if len(above) != 1:
                break
            tower.append(above[0])
        in_tower = {t["name"] for t in tower if not t["tilted"]}
        bad = [r["name"] for r in group if r["name"] not in in_tower]
        if bad or len(bottom) != (1 if group else 0) or len(in_tower) != len(names):
            bad = bad or [r["name"] for r in bottom[1:]]
            failures.add(f"not one upright stack of {len(group)}: {', '.join(map(_short, bad))} off the tower", bad)

    def require_layers(objs: Any, counts: Sequence[int]) -> None:
        group = objs_of(objs)
        failures.demands.append(("layers", names_of(group), tuple(int(c) for c in counts)))
        have = [sum(1 for r in group if r["level"] == k + 1) for k in range(max(len(counts), 1))]
        bad = [r["name"] for r in group if r["tilted"] or r["level"] > len(counts)]
        if list(have) != list(counts) or bad:
            top = [r["name"] for r in group if r["level"] == max((x["level"] for x in group), default=1)]
            failures.add(f"layers (bottom first) hold {have}, not {list(counts)}", bad or top)

    def require_on_table(objs: Any) -> None:
        group = objs_of(objs)
        failures.demands.append(("table", names_of(group), None))
        bad = [r["name"] for r in group if r["level"] != 1 or r["tilted"]]
        if bad:
            failures.add(f"not upright on the table: {', '.join(map(_short, bad))}", bad)

    def require_unmoved(objs: Any) -> None:
        bad = [r["name"] for r in objs_of(objs)
               if math.dist(r["centre"][:2], start[r["name"]]["centre"][:2]) > MOVE_TOL]
        if bad:
            failures.add(f"moved from where they started: {', '.join(map(_short, bad))}", bad)

    def require_circle(objs: Any, around: Any = None) -> None:
        group = objs_of(objs)
        centre, radius, resid = fit_circle([r["centre"] for r in group])
        if not math.isfinite(radius) or resid > CIRCLE_TOL:
            dist = [abs(math.dist(r["centre"][:2], centre) - radius) if math.isfinite(radius) else 0.0 for r in group]
            worst = [group[int(np.argmax(dist))]["name"]] if group else []
            failures.add("the centres are not on one circle", worst)
            return
        if around is not None:
            mid = objs_of(around, "around")[0]
            if math.dist(mid["centre"][:2], centre) > CENTRE_TOL:
                failures.add(f"the circle is not centred on the {_short(mid['name'])}", [r["name"] for r in group])

    def require_row(objs: Any) -> None:
        group = objs_of(objs)
        xy = np.array([r["centre"][:2] for r in group], dtype=float).reshape(-1, 2)
        if len(xy) < 2:
            return
        q = xy - xy.mean(axis=0)
        direction = np.linalg.svd(q)[2][0]
        off = np.abs(q @ np.array([-direction[1], direction[0]]))
        if off.max() > ROW_LINE_TOL:
            failures.add("the centres are not on one straight line", [group[int(np.argmax(off))]["name"]])

    def require_alternating(objs: Any, first_color: str | None = None, around: Any = None) -> None:
        group = objs_of(objs)
        if len({r["level"] for r in group}) == len(group):  # a stack: bottom first
            order, cyclic = sorted(group, key=lambda r: r["level"]), False
        else:  # a ring or a group on the table: around the object `around` (as in require_circle), else their centre
            mid = (objs_of(around, "around")[0]["centre"][:2] if around is not None
                   else np.mean([r["centre"][:2] for r in group], axis=0))
            order = sorted(group, key=lambda r: math.atan2(r["centre"][1] - mid[1], r["centre"][0] - mid[0]))
            cyclic = True
        pairs = list(zip(order, order[1:] + (order[:1] if cyclic and len(order) > 2 else [])))
        bad = [b["name"] for a, b in pairs if a["color"] == b["color"]]
        if first_color is not None and order and not cyclic and order[0]["color"] != first_color:
            bad = [order[0]["name"]] + bad
        if bad:
            failures.add(f"colours do not alternate ({' '.join(r['color'] for r in order)})", bad)

    def require_count(objs: Any, place: Any, n: int) -> None:
        where = place_of(place)
        group = objs_of(objs)
        failures.demands.append(("count", names_of(group), int(n)))
        inside = [r["name"] for r in group if is_in(r, where)]
        if len(inside) != int(n):
            bad = inside if len(inside) > n else [r["name"] for r in group if r["name"] not in inside]
            failures.add(f"{len(inside)} of them in the {said(where)}, not {n}", bad)

    def require_different_colors(objs: Any) -> None:
        group = objs_of(objs)
        seen: dict[str, str] = {}
        bad = []
        for r in group:
            if r["color"] in seen:
                bad.append(r["name"])
            seen.setdefault(r["color"], r["name"])
        if bad:
            failures.add(f"colours repeat: {', '.join(map(_short, bad))}", bad)

    env: dict[str, Any] = {
        "objects": rows,
        "blocks": blocks, "other_blocks": other_blocks, "blocks_beside": blocks_beside,
        "zone": lambda color=None: the("zone", color), "bowl": lambda color=None: the("bowl", color),
        "ball": lambda color=None: the("ball", color),
        "zones": lambda: [r for r in rows if r["kind"] == "zone"], "bowls": lambda: [r for r in rows if r["kind"] == "bowl"],
    }
    local = locals()
    env.update({name: checked(name, local[name]) for name in CHECKS})
    return env, failures
