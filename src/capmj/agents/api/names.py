"""Object names at the planner API: the exact, forgiving and near-miss readings of a name, and
the error that says what was meant when none fits.

Plan code writes names as small models write them ("brown bowl", "movable_blue_block_with_obj_id_3",
"yellow block with obj_id 4"); :func:`lookup` accepts exactly the readings that can mean one object
and nothing else, so a name is never guessed.  Shared by the planner API (:mod:`capmj.agents.api.planner_api`)
and the reporter's scene (:mod:`capmj.agents.report.text_env`), so both read a name the same way.
"""

from __future__ import annotations

import difflib
import re
from typing import Any, Sequence

import numpy as np

from capmj.agents.api.values import summary as _summary
from capmj.errors import PortingDifference, UnknownObjectError
from capmj.sim.objects import ObjectSpec

_FILLER = frozenset({"the", "a", "an", "with", "obj", "id", "object", "of"})


def _words(text: str) -> list[str]:
    return re.findall(r"[a-z]+|\d+", text.lower().replace("_", " "))


def near_miss(query: str, objects: Sequence[ObjectSpec]) -> ObjectSpec | None:
    """The one object a near-miss name can only mean, else None.

    The query's words (case, ``_`` and punctuation ignored; "the", "with", "obj_id" ... dropped)
    must all be words of the object's name, and a number in the query must be its obj_id:
    ``'brown bowl'`` (one brown bowl), ``'movable_blue_block_with_obj_id_3'``, ``'yellow block
    with obj_id 4'``.  Two or more fitting objects, or none, give None: nothing is guessed.
    """
    words = _words(query)
    ids = {int(w) for w in words if w.isdigit()}
    words = [w for w in words if not w.isdigit() and w not in _FILLER]
    if len(ids) > 1 or not (words or ids):
        return None
    fits = [o for o in objects if (not ids or o.obj_id in ids) and set(words) <= set(_words(o.name))]
    return fits[0] if len(fits) == 1 else None


def porting_difference(obj: str, objs: Sequence[ObjectSpec]) -> None:
    """PortingDifference for an unknown name that CapRavens' scenes could have had: a fixed
    block (capmj's blocks are all movable) or obj_id 0 (capmj's ids count from 1)."""
    words = _words(obj)
    if "fixed" in words:
        fit = near_miss(" ".join(w for w in words if w != "fixed"), objs)
        if fit is not None and not fit.fixed:
            raise PortingDifference(f"unknown object {obj!r}: capmj has no fixed {fit.kind}s (every {fit.kind} "
                                    f"is movable, unlike CapRavens' fixed blocks); the {fit.kind} meant is "
                                    f"{fit.name!r}")
    if re.search(r"obj_id\s*0\b", obj):
        raise PortingDifference(f"unknown object {obj!r}: capmj's obj_ids count from 1 (CapRavens' were "
                                f"PyBullet body ids); valid ids: {sorted(o.obj_id for o in objs)}")


def _closest(query: str, names: Sequence[str], n: int = 3) -> list[str]:
    """Names sharing the most words with ``query`` (ties by string similarity)."""
    words = set(_words(query)) - _FILLER

    def score(name: str) -> tuple[int, float]:
        return (len(words & set(_words(name))), difflib.SequenceMatcher(None, query.lower(), name.lower()).ratio())

    return sorted(names, key=score, reverse=True)[:n]


def lookup(obj: Any, objs: Sequence[ObjectSpec]) -> tuple[ObjectSpec, bool]:
    """The spec of a name (exact; case and spacing forgiven; else a :func:`near_miss`) or an int
    obj_id, and whether it was a near miss (which the API logs); else UnknownObjectError (or
    :class:`~capmj.errors.PortingDifference`) naming the closest and the valid names."""
    if isinstance(obj, (int, np.integer)) and not isinstance(obj, bool):
        for o in objs:
            if o.obj_id == int(obj):
                return o, False
        raise UnknownObjectError(f"no object with obj_id {int(obj)}; valid ids: {sorted(o.obj_id for o in objs)}",
                                 name=int(obj))
    if not isinstance(obj, str):
        raise ValueError(f"expected an object name (str), got {type(obj).__name__} {_summary(obj, 80)}")
    for o in objs:
        if o.name == obj:
            return o, False
    key = " ".join(obj.lower().split())
    for o in objs:
        if o.name.lower() == key:
            return o, False
    fit = near_miss(obj, objs)
    if fit is not None:
        return fit, True
    porting_difference(obj, objs)
    names = [o.name for o in objs]
    close = _closest(obj, names)
    hint = f"; closest names: {', '.join(map(repr, close))}" if close else ""
    shown = names[:6]
    more = f" … ({len(names)} objects)" if len(names) > len(shown) else ""
    raise UnknownObjectError(f"unknown object {obj!r}{hint}. Valid names: {', '.join(map(repr, shown))}{more}",
                             name=obj)
