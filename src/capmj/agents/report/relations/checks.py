"""Pre-bound relation checks over a measured scene: what the ``relations`` reporter's code calls.

The model only says *which* relations the goal asks for, as calls such as
``require_inside(blocks(color="red"), zone("green"))``; each call measures its relation on the
records and, when it fails, records a sentence and the names of the objects that break it.  The
verdict is "achieved" exactly when no call failed, and ``wrong`` is the union of the names, so a
"not achieved" always names objects.

The relations are generic to tabletop goals (inside, outside, one stack, layers, on the table,
unmoved, a circle, a row, alternating colours, a count, distinct colours); each is measured from
the records of :mod:`capmj.agents.report.scene` with the tasks' own tolerances
(:mod:`capmj.tasks.predicates`), as the records themselves are.  No call knows any task.

:func:`relation_env` builds the names a check may use for one scene: the selectors of
:mod:`capmj.agents.report.relations.picks` (which also read what each check is given: a record, a list of
records, a name, a colour word where a zone or bowl is meant) and the checks here;
:class:`Failures` collects what failed.  Anything a check cannot read raises
:class:`~capmj.errors.CheckArgumentError` with the valid choices, which the repair request quotes.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from capmj.agents.report.relations.picks import SELECTORS, Picks, Record, short
from capmj.agents.report.scene import AREAS
from capmj.tasks.predicates import CENTRE_TOL, CIRCLE_TOL, ROW_LINE_TOL, fit_circle
from capmj.tasks.predicates.tolerances import MOVE_TOL

__all__ = ["CHECKS", "NAMES", "SELECTORS", "Failures", "relation_env"]

CHECKS = ("require_inside", "require_outside", "require_stack", "require_layers", "require_on_table",
          "require_unmoved", "require_circle", "require_row", "require_alternating", "require_count",
          "require_different_colors")
"""The relation checks, in the order the prompt documents them."""
NAMES = ("objects", *SELECTORS, *CHECKS)
"""Every name :func:`relation_env` binds: what a check may use besides Python's builtins."""


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
            for name in sorted(names):  # sorted: the repair request must not vary with string hashing
                {"inside": inside, "outside": outside}.get(relation, {}).setdefault(name, []).append(detail)
            if relation == "stack" and len(names) > 1:
                stacks.append(names)
            tables += [names] if relation == "table" else []
            layers += [(names, detail)] if relation == "layers" else []
        for name, places in inside.items():
            if any(p <= q for p in places for q in outside.get(name, [])):
                return f"it requires {short(name)} both in and out of the same place"
            containers = [p for p in places if not p & set(AREAS)]
            if any(not p & q for p in containers for q in containers):
                return f"it requires {short(name)} in two different places at once"
        for tower in stacks:
            if any(len(tower & t) > 1 for t in tables):
                return "it requires the same objects in one tower and all on the table"
            if tower in self.layered_towers():
                return ("it requires the same objects in one tower and in layers of several: a tower is a single column; "
                        "a structure with several blocks in a layer is require_layers alone")
        return None

    def layered_towers(self) -> frozenset[frozenset[str]]:
        """The groups of objects required both as one tower and in layers of several blocks.

        No scene passes both, and the prompt says which one a structure is ("a structure with
        several blocks in a layer is require_layers"), so :func:`relation_env` can read such a tower
        as its place only (``layered``)."""
        towers = {names for relation, names, _ in self.demands if relation == "stack" and len(names) > 1}
        return frozenset(names for relation, names, counts in self.demands
                         if relation == "layers" and names in towers and max(counts, default=0) > 1)

    @property
    def wrong(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(n for _, ns in self.items for n in ns))

    @property
    def reason(self) -> str:
        return "; ".join(s for s, _ in self.items) if self.items else "every required relation holds"


def _names(group: Sequence[Record]) -> frozenset[str]:
    return frozenset(r["name"] for r in group)


class _Checks:
    """The relation checks over one scene's :class:`~capmj.agents.report.relations.picks.Picks`: each measures its
    relation and adds what fails to :class:`Failures` (and what it asked for, for :meth:`Failures.impossible`)."""

    def __init__(self, picks: Picks, failures: Failures, layered: frozenset[frozenset[str]]) -> None:
        self.p, self.f, self.layered = picks, failures, layered

    def require_inside(self, objs: Any, place: Any) -> None:
        where, group = self.p.places(place), self.p.objs(objs)
        self.f.demands.append(("inside", _names(group), frozenset(where)))
        bad = [r["name"] for r in group if not self.p.is_in(r, where)]
        if bad:
            self.f.add(f"not in the {self.p.said(where)}: {', '.join(map(short, bad))}", bad)

    def require_outside(self, objs: Any, place: Any) -> None:
        where, group = self.p.places(place), self.p.objs(objs)
        self.f.demands.append(("outside", _names(group), frozenset(where)))
        bad = [r["name"] for r in group if self.p.is_in(r, where)]
        if bad:
            self.f.add(f"must not be in the {self.p.said(where)}: {', '.join(map(short, bad))}", bad)

    def require_stack(self, objs: Any, place: Any = None) -> None:
        group = self.p.objs(objs)
        if place is not None:
            self.require_inside(group, place)
        names = _names(group)
        if names in self.layered:  # also required in layers of several: those say the shape
            return
        self.f.demands.append(("stack", names, None))
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
            self.f.add(f"not one upright stack of {len(group)}: {', '.join(map(short, bad))} off the tower", bad)

    def require_layers(self, objs: Any, counts: Sequence[int]) -> None:
        group = self.p.objs(objs)
        self.f.demands.append(("layers", _names(group), tuple(int(c) for c in counts)))
        have = [sum(1 for r in group if r["level"] == k + 1) for k in range(max(len(counts), 1))]
        bad = [r["name"] for r in group if r["tilted"] or r["level"] > len(counts)]
        if list(have) != list(counts) or bad:
            top = [r["name"] for r in group if r["level"] == max((x["level"] for x in group), default=1)]
            self.f.add(f"layers (bottom first) hold {have}, not {list(counts)}", bad or top)

    def require_on_table(self, objs: Any) -> None:
        group = self.p.objs(objs)
        self.f.demands.append(("table", _names(group), None))
        bad = [r["name"] for r in group if r["level"] != 1 or r["tilted"]]
        if bad:
            self.f.add(f"not upright on the table: {', '.join(map(short, bad))}", bad)

    def require_unmoved(self, objs: Any) -> None:
        bad = [r["name"] for r in self.p.objs(objs)
               if math.dist(r["centre"][:2], self.p.start[r["name"]]["centre"][:2]) > MOVE_TOL]
        if bad:
            self.f.add(f"moved from where they started: {', '.join(map(short, bad))}", bad)

    def require_circle(self, objs: Any, around: Any = None) -> None:
        group = self.p.objs(objs)
        centre, radius, resid = fit_circle([r["centre"] for r in group])
        if not math.isfinite(radius) or resid > CIRCLE_TOL:
            dist = [abs(math.dist(r["centre"][:2], centre) - radius) if math.isfinite(radius) else 0.0 for r in group]
            worst = [group[int(np.argmax(dist))]["name"]] if group else []
            self.f.add("the centres are not on one circle", worst)
            return
        if around is not None:
            mid = self.p.objs(around, "around")[0]
            if math.dist(mid["centre"][:2], centre) > CENTRE_TOL:
                self.f.add(f"the circle is not centred on the {short(mid['name'])}", [r["name"] for r in group])

    def require_row(self, objs: Any) -> None:
        group = self.p.objs(objs)
        xy = np.array([r["centre"][:2] for r in group], dtype=float).reshape(-1, 2)
        if len(xy) < 2:
            return
        q = xy - xy.mean(axis=0)
        direction = np.linalg.svd(q)[2][0]
        off = np.abs(q @ np.array([-direction[1], direction[0]]))
        if off.max() > ROW_LINE_TOL:
            self.f.add("the centres are not on one straight line", [group[int(np.argmax(off))]["name"]])

    def require_alternating(self, objs: Any, first_color: str | None = None, around: Any = None) -> None:
        group = self.p.objs(objs)
        if len({r["level"] for r in group}) == len(group):  # a stack: bottom first
            order, cyclic = sorted(group, key=lambda r: r["level"]), False
        else:  # a ring or a group on the table: around the object `around` (as in require_circle), else their centre
            mid = (self.p.objs(around, "around")[0]["centre"][:2] if around is not None
                   else np.mean([r["centre"][:2] for r in group], axis=0))
            order = sorted(group, key=lambda r: math.atan2(r["centre"][1] - mid[1], r["centre"][0] - mid[0]))
            cyclic = True
        pairs = list(zip(order, order[1:] + (order[:1] if cyclic and len(order) > 2 else [])))
        bad = [b["name"] for a, b in pairs if a["color"] == b["color"]]
        if first_color is not None and order and not cyclic and order[0]["color"] != first_color:
            bad = [order[0]["name"]] + bad
        if bad:
            self.f.add(f"colours do not alternate ({' '.join(r['color'] for r in order)})", bad)

    def require_count(self, objs: Any, place: Any, n: int) -> None:
        where = self.p.places(place)
        group = self.p.objs(objs)
        self.f.demands.append(("count", _names(group), int(n)))
        inside = [r["name"] for r in group if self.p.is_in(r, where)]
        if len(inside) != int(n):
            bad = inside if len(inside) > n else [r["name"] for r in group if r["name"] not in inside]
            self.f.add(f"{len(inside)} of them in the {self.p.said(where)}, not {n}", bad)

    def require_different_colors(self, objs: Any) -> None:
        group = self.p.objs(objs)
        seen: dict[str, str] = {}
        bad = []
        for r in group:
            if r["color"] in seen:
                bad.append(r["name"])
            seen.setdefault(r["color"], r["name"])
        if bad:
            self.f.add(f"colours repeat: {', '.join(map(short, bad))}", bad)


def relation_env(rows: Sequence[Record], start_rows: Sequence[Record] | None = None,
                 layered: frozenset[frozenset[str]] = frozenset()) -> tuple[dict[str, Any], Failures]:
    """The names a check may use over the scene ``rows`` (records), and the :class:`Failures` its calls fill.

    ``start_rows``: the records of the scene the robot started from (for ``require_unmoved``; the
    scene itself when None).  ``layered``: groups (of names) whose ``require_stack`` asks only for
    its place, because the check also requires them in layers (:meth:`Failures.layered_towers`)."""
    picks = Picks(rows, start_rows)
    failures = Failures(empty_picks=picks.empty_picks)
    checks = _Checks(picks, failures, layered)

    def counted(name: str) -> Callable[..., None]:
        fn = getattr(checks, name)

        def run(*args: Any, **kwargs: Any) -> None:
            failures.calls += 1
            try:
                fn(*args, **kwargs)
            except TypeError as exc:  # "require_count() missing ... 'n'", as the model called it, not "_Checks.require_count()"
                raise TypeError(str(exc).replace(f"{_Checks.__name__}.", "")) from None
        run.__name__ = name
        return run

    return {**picks.bindings(), **{name: counted(name) for name in CHECKS}}, failures
