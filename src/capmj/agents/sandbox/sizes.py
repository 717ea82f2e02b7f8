"""How big a plan value would be as text or as a numpy array, found without making either.

Plan code can build a small object that stands for a huge one: ``a = [0] * 1000; b = [a] * 1000;
c = [b] * 100`` holds 1 100 list slots, but ``str(c)`` is 300 MB of text and ``np.array(c)`` 100
million numbers.  Every place that turns a plan value into text (``print``, ``say``, a helper's
return value, an error message, the call log) or into an array (``np.array``, arithmetic with an
array, any numpy function given a list) therefore asks this module first:

* :func:`text_length` walks the value as ``repr``/``str`` would and stops as soon as the count
  passes the limit, so the work is bounded by the limit, never by the size of the text;
  :func:`capped_text` makes the real text only when it fits, and :func:`preview` gives the
  first characters of any value (for logs: never raises, never makes more than its limit).
* :func:`array_elements` counts the elements ``np.asarray`` would allocate for a nested sequence,
  walking each list object once however often it is shared (so the count of ``c`` above costs
  about 2 000 steps) and stopping past the cap; wide string leaves count by their bytes.
* :func:`broadcast_elements` is the size of the result of an element-wise operation on arrays
  (numpy's broadcasting rules, via ``np.broadcast_shapes``), and :func:`matmul_elements` and
  :func:`dot_elements` those of matrix products; all of them before anything is computed.

Containers are walked exactly as CPython and numpy print them; a value of any other type is
printed by its own ``repr`` (the sandbox offers no other type whose text holds plan values).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as _np

from capmj.agents.sandbox.ordered import OrderedFrozenSet, OrderedSet

__all__ = ["array_elements", "array_shape", "broadcast_elements", "capped_text", "dot_elements",
           "matmul_elements", "preview", "text_length"]

_MAX_DEPTH = 64
"""Deeper nesting than this is not followed (numpy refuses more than 64 dimensions anyway)."""

_DICT_VIEWS: tuple[type, ...] = (type({}.keys()), type({}.values()), type({}.items()))


class _Over(Exception):
    """The text passed its limit (internal to the walk)."""


class _Text:
    """Counts (and, for a preview, keeps) the pieces of a text; raises :class:`_Over` past ``limit``."""

    __slots__ = ("limit", "n", "parts", "keep")

    def __init__(self, limit: int, keep: bool) -> None:
        self.limit, self.n, self.keep = limit, 0, keep
        self.parts: list[str] = []

    def room(self) -> int:
        return self.limit - self.n

    def put(self, piece: str) -> None:
        if self.keep:
            self.parts.append(piece[: max(self.room(), 0) + 1])
        self.n += len(piece)
        if self.n > self.limit:
            raise _Over

    def text(self) -> str:
        return "".join(self.parts)


def _items(out: _Text, items: Iterable[Any], stack: set[int], depth: int) -> None:
    for i, item in enumerate(items):
        if i:
            out.put(", ")
        _write(item, out, stack, False, depth)


def _write_str(value: str | bytes | bytearray, out: _Text, as_str: bool) -> None:
    if as_str and isinstance(value, str):
        out.put(value)
        return
    # repr is at least len + 2 and at most 4 (bytes) or 10 (str) characters per character
    if len(value) + 2 > out.room():
        out.put(repr(value[: out.room() + 1]))
    out.put(repr(value))


def _write_array(value: _np.ndarray, out: _Text, stack: set[int], as_str: bool, depth: int) -> None:
    kind = value.dtype.kind
    if kind == "O":  # elements are plan values: walk them
        out.put("array(")
        if value.ndim == 0:
            _write(value.item(), out, stack, False, depth + 1)
        else:
            out.put("[")
            _items(out, iter(value) if value.ndim > 1 else value.flat, stack, depth + 1)
            out.put("]")
        out.put(", dtype=object)")
        return
    if kind in "USV":  # printed elements can be as wide as the item size
        shown = value.size if value.size <= _np.get_printoptions()["threshold"] else 6 * max(value.ndim, 1)
        if shown * (value.dtype.itemsize + 4) > out.room():
            raise _Over
    out.put(str(value) if as_str else repr(value))  # numpy summarises large arrays itself


def _write(value: Any, out: _Text, stack: set[int], as_str: bool, depth: int = 0) -> None:
    """Put the text of ``value`` (``str`` when ``as_str``, else ``repr``) into ``out``."""
    if isinstance(value, (str, bytes, bytearray)):
        if isinstance(value, bytearray):
            out.put("bytearray(")
            _write_str(bytes(value[: out.room() + 1]) if len(value) > out.room() else bytes(value), out, False)
            out.put(")")
        else:
            _write_str(value, out, as_str)
        return
    if depth > _MAX_DEPTH:
        raise _Over  # deeper than any plan value needs: counted as too long
    if isinstance(value, _np.ndarray):
        _write_array(value, out, stack, as_str, depth)
        return
    if isinstance(value, BaseException):
        key = id(value)
        if key in stack:
            out.put("...")
            return
        stack.add(key)
        try:
            _write_exception(value, out, stack, as_str, depth)
        finally:
            stack.discard(key)
        return
    opening = _opening(value)
    if opening is None:
        out.put(str(value) if as_str else repr(value))  # a leaf: its own text is bounded
        return
    start, end = opening
    key = id(value)
    if key in stack:  # a container inside itself
        out.put(start + "..." + end)
        return
    stack.add(key)
    try:
        out.put(start)
        if isinstance(value, (dict, *_DICT_VIEWS[2:])) and not isinstance(value, _DICT_VIEWS[:2]):
            pairs: Any = value.items() if isinstance(value, dict) else value
            for i, (k, v) in enumerate(pairs):
                if i:
                    out.put(", ")
                if isinstance(value, dict):
                    _write(k, out, stack, False, depth + 1)
                    out.put(": ")
                    _write(v, out, stack, False, depth + 1)
                else:
                    out.put("(")
                    _write(k, out, stack, False, depth + 1)
                    out.put(", ")
                    _write(v, out, stack, False, depth + 1)
                    out.put(")")
        elif isinstance(value, slice):
            _items(out, (value.start, value.stop, value.step), stack, depth + 1)
        elif isinstance(value, (list, tuple)) and len(value) <= out.room() and _all_short(value):
            out.put(repr(value)[len(start):])  # a flat run of numbers: printed at C speed, bounded
            return
        else:
            for i, item in enumerate(value):
                if i:
                    out.put(", ")
                _write(item, out, stack, False, depth + 1)
            if isinstance(value, tuple) and len(value) == 1:
                out.put(",")
        out.put(end)
    finally:
        stack.discard(key)


_SHORT_INT = 10**18


def _all_short(items: list[Any] | tuple[Any, ...]) -> bool:
    """Whether every item prints in a few characters (a float, a bool, None, a small int)."""
    return all(isinstance(x, float) or x is None or (type(x) in (int, bool) and -_SHORT_INT < x < _SHORT_INT)
               for x in items)


def _opening(value: Any) -> tuple[str, str] | None:
    """The brackets around a container's items, None for a leaf."""
    if isinstance(value, list):
        return "[", "]"
    if isinstance(value, tuple):
        return "(", ")"
    if isinstance(value, dict):
        return "{", "}"
    if isinstance(value, (OrderedSet, set)):
        return ("{", "}") if len(value) else ("set(", ")")
    if isinstance(value, (OrderedFrozenSet, frozenset)):
        return ("frozenset({", "})") if len(value) else ("frozenset(", ")")
    if isinstance(value, _DICT_VIEWS):
        return f"{type(value).__name__}([", "])"
    if isinstance(value, slice):
        return "slice(", ")"
    return None


def _write_exception(exc: BaseException, out: _Text, stack: set[int], as_str: bool, depth: int) -> None:
    args = exc.args if isinstance(exc.args, tuple) else ()
    if as_str:
        if len(args) == 1:
            _write(args[0], out, stack, not isinstance(exc, KeyError), depth + 1)
        elif args:
            _write(args, out, stack, False, depth + 1)
        return
    out.put(f"{type(exc).__name__}(")
    _items(out, args, stack, depth + 1)
    out.put(")")


def text_length(value: Any, limit: int, *, as_repr: bool = False) -> int | None:
    """The length of ``str(value)`` (``repr`` with ``as_repr``) when it is at most ``limit``
    characters, else None; the work is bounded by ``limit``, whatever the value holds."""
    out = _Text(limit, keep=False)
    try:
        _write(value, out, set(), not as_repr)
    except _Over:
        return None
    return out.n


def capped_text(value: Any, limit: int, *, as_repr: bool = False) -> str | None:
    """``str(value)`` (``repr`` with ``as_repr``) when it has at most ``limit`` characters, else
    None, without making the text in that case.  Errors of the value's own text propagate."""
    if text_length(value, limit, as_repr=as_repr) is None:
        return None
    return repr(value) if as_repr else str(value)


def preview(value: Any, limit: int, *, as_repr: bool = True) -> str:
    """``repr(value)`` (``str`` without ``as_repr``) when it has at most ``limit`` characters, else
    its first ``limit - 3`` characters and ``...``.  Never raises and never makes more than about
    ``limit`` characters: for logs and messages about any plan value."""
    out = _Text(limit, keep=True)
    try:
        _write(value, out, set(), not as_repr)
        text = repr(value) if as_repr else str(value)  # it fits: the value's own text, exactly
    except _Over:
        text = out.text()
    except Exception as exc:  # noqa: BLE001 - a value whose own text fails must not break a log
        return f"<unrepresentable {type(value).__name__}: {type(exc).__name__}>"
    return text if len(text) <= limit else text[: max(limit - 3, 0)] + "..."


# ------------------------------------------------------------------------------------------------
# arrays
# ------------------------------------------------------------------------------------------------
class _TooMany(Exception):
    """The count passed its cap (internal to the walk)."""


def _leaf_words(value: Any) -> int:
    """Eight-byte words one element takes in the array numpy would make (wide strings take more)."""
    if isinstance(value, str):
        return max(1, -(-4 * len(value) // 8))
    if isinstance(value, (bytes, bytearray)):
        return max(1, -(-len(value) // 8))
    return 1


def array_elements(value: Any, cap: int) -> int:
    """Elements (in eight-byte words) ``np.asarray(value)`` would allocate: an array's size, a
    nested list's or tuple's leaves (a list that appears many times is walked once and counted
    each time it appears), one for anything else.  Returns a number above ``cap`` as soon as the
    count passes it, so the work is bounded by the distinct objects walked."""
    if isinstance(value, _np.ndarray):
        return int(value.size) * max(1, -(-value.dtype.itemsize // 8))
    if not isinstance(value, (list, tuple)):
        return 0
    memo: dict[int, tuple[int, int]] = {}  # id -> (leaves, widest leaf in words); all alive during the walk

    def walk(obj: Any, depth: int) -> tuple[int, int]:
        if isinstance(obj, _np.ndarray):
            return int(obj.size), max(1, -(-obj.dtype.itemsize // 8))
        if not isinstance(obj, (list, tuple)) or depth > _MAX_DEPTH:
            return 1, _leaf_words(obj)
        key = id(obj)
        if key in memo:
            return memo[key]
        memo[key] = (0, 1)  # a list inside itself counts nothing more (numpy refuses it)
        leaves, widest = 0, 1
        for item in obj:
            n, w = walk(item, depth + 1)
            leaves += n
            widest = max(widest, w)
            if leaves * widest > cap:
                raise _TooMany
        memo[key] = (leaves, widest)
        return leaves, widest

    try:
        leaves, widest = walk(value, 0)
    except _TooMany:
        return cap + 1
    return leaves * widest


def array_shape(value: Any) -> tuple[int, ...]:
    """The shape numpy would give ``value``: an array's own, a nested sequence's along its first
    items (what numpy finds for a regular nesting; a ragged one fails in numpy), ``()`` otherwise."""
    if isinstance(value, (_np.ndarray, _np.generic)):
        return tuple(value.shape)
    shape: list[int] = []
    while isinstance(value, (list, tuple)) and len(shape) < _MAX_DEPTH:
        shape.append(len(value))
        if not value:
            break
        value = value[0]
    if isinstance(value, _np.ndarray):
        shape.extend(value.shape)
    return tuple(shape)


def _product(shape: Iterable[int]) -> int:
    return math.prod(int(d) for d in shape)


def broadcast_elements(*operands: Any) -> int:
    """Elements of the result of an element-wise operation on ``operands`` (numpy broadcasting);
    for shapes that do not broadcast (numpy raises) the largest operand's size."""
    shapes = [array_shape(x) for x in operands]
    try:
        return _product(_np.broadcast_shapes(*shapes))
    except ValueError:
        return max((_product(s) for s in shapes), default=0)


def matmul_elements(a: Any, b: Any) -> int:
    """Elements of ``a @ b`` (``np.matmul``): the broadcast batch dimensions times rows times columns."""
    sa, sb = array_shape(a), array_shape(b)
    if not sa or not sb:
        return broadcast_elements(a, b)
    rows = sa[-2] if len(sa) > 1 else 1
    cols = sb[-1] if len(sb) > 1 else 1
    try:
        batch = _product(_np.broadcast_shapes(sa[:-2], sb[:-2]))
    except ValueError:
        batch = max(_product(sa[:-2]), _product(sb[:-2]))
    return batch * rows * cols


def dot_elements(a: Any, b: Any) -> int:
    """Elements of ``np.dot(a, b)``: every axis of ``a`` but its last, with every axis of ``b`` but
    its second-to-last (a scalar operand multiplies element-wise)."""
    sa, sb = array_shape(a), array_shape(b)
    if not sa or not sb:
        return broadcast_elements(a, b)
    kept_b = sb[:-2] + sb[-1:] if len(sb) > 1 else ()
    return _product(sa[:-1]) * _product(kept_b)
