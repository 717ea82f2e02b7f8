"""Insertion-ordered ``set`` and ``frozenset`` for LLM code: the same iteration order everywhere.

Why: Python randomises string hashing per process, so ``for c in set(colors)`` visits the
colours in a different order in every worker, and a cached plan that stacks blocks in set order
built a different tower on every replay.  Inside the sandbox the names ``set`` and
``frozenset``, set literals and set comprehensions make these classes instead, whose order is
the order of insertion (like ``dict``), independent of hashing.  Real sets are registered as
virtual subclasses, so ``isinstance(real_set, set)`` stays true in LLM code.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Iterator, MutableSet, Set
from typing import Any

__all__ = ["OrderedFrozenSet", "OrderedSet"]


class _Ordered(Set):
    """Shared read-only part: a dict's keys as the elements."""

    __slots__ = ("_items",)

    def __init__(self, iterable: Iterable[Any] = ()) -> None:
        self._items: dict[Any, None] = dict.fromkeys(iterable)

    @classmethod
    def _from_iterable(cls, it: Iterable[Any]) -> Any:
        return cls(it)

    def __contains__(self, item: object) -> bool:
        return item in self._items

    def __iter__(self) -> Iterator[Any]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        name = "set" if isinstance(self, OrderedSet) else "frozenset"
        if not self._items:
            return f"{name}()"
        body = "{" + ", ".join(repr(x) for x in self._items) + "}"
        return body if name == "set" else f"frozenset({body})"

    def __reduce__(self) -> tuple[Any, ...]:
        return type(self), (list(self._items),)

    # the named methods of the builtin types (the operators come from collections.abc.Set)
    def union(self, *others: Iterable[Any]) -> Any:
        out = type(self)(self)
        for other in others:
            out = type(self)(list(out) + [x for x in other if x not in out])
        return out

    def intersection(self, *others: Iterable[Any]) -> Any:
        pools = [o if isinstance(o, (Set, dict)) else list(o) for o in others]
        return type(self)(x for x in self if all(x in pool for pool in pools))

    def difference(self, *others: Iterable[Any]) -> Any:
        drop: list[Any] = [x for o in others for x in o]
        return type(self)(x for x in self if x not in drop)

    def symmetric_difference(self, other: Iterable[Any]) -> Any:
        other = type(self)(other)
        return type(self)([x for x in self if x not in other] + [x for x in other if x not in self])

    def issubset(self, other: Iterable[Any]) -> bool:
        other = other if isinstance(other, Set) else type(self)(other)
        return all(x in other for x in self)

    def issuperset(self, other: Iterable[Any]) -> bool:
        return all(x in self for x in other)

    def copy(self) -> Any:
        return type(self)(self)


class OrderedSet(_Ordered, MutableSet):
    """``set`` for LLM code, iterating in insertion order."""

    __slots__ = ()
    __hash__ = None  # type: ignore[assignment]

    def add(self, item: Any) -> None:
        self._items[item] = None

    def discard(self, item: Any) -> None:
        self._items.pop(item, None)

    def remove(self, item: Any) -> None:
        if item not in self._items:
            raise KeyError(item)
        del self._items[item]

    def pop(self) -> Any:
        if not self._items:
            raise KeyError("pop from an empty set")
        item = next(iter(self._items))
        del self._items[item]
        return item

    def clear(self) -> None:
        self._items.clear()

    def update(self, *others: Iterable[Any]) -> None:
        for other in others:
            for x in other:
                self._items[x] = None

    def intersection_update(self, *others: Iterable[Any]) -> None:
        self._items = dict.fromkeys(self.intersection(*others))

    def difference_update(self, *others: Iterable[Any]) -> None:
        self._items = dict.fromkeys(self.difference(*others))

    def symmetric_difference_update(self, other: Iterable[Any]) -> None:
        self._items = dict.fromkeys(self.symmetric_difference(other))


class OrderedFrozenSet(_Ordered, Hashable):
    """``frozenset`` for LLM code, iterating in insertion order; hashable."""

    __slots__ = ()

    def __hash__(self) -> int:
        return self._hash()


OrderedSet.register(set)
OrderedFrozenSet.register(frozenset)
