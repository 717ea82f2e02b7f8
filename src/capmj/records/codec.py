"""Frozen record dataclasses <-> plain JSON data, strict by default.

Why one generic codec: every record type (:mod:`capmj.records.attempt`, :mod:`.notes`,
:mod:`.episode`) is a frozen dataclass whose field annotations already say what each key holds, so
reading one back is the same walk everywhere: a key the type does not know, a key it needs that is
missing, or a value of the wrong kind is a :class:`~capmj.errors.RecordError` naming the record and
the key, not a ``KeyError`` three modules later.

Conventions a record type opts into with class attributes:

* ``OMIT_IF_NONE``: keys left out of the dict while their value is None (keys that files written
  today hold only sometimes, e.g. an attempt's ``api_error``); missing on reading means None.
* ``EMPTY_IF_NONE``: record-valued keys written as ``{}`` while None (``llm`` of a non-LLM episode).
* ``DEFAULT_IF_MISSING``: keys added to a record after lines of its schema were written (always
  written now); missing on reading means the field's default.  Why not a new schema: the older
  lines mean exactly the default (e.g. no ``loop_policy``: the only loop there was, ``thesis``).

A ``float`` may be None: :func:`capmj.bench.results.sanitize` writes non-finite floats as null.
``strict=False`` (legacy migration only) ignores unknown keys and fills missing ones from defaults.
"""

from __future__ import annotations

import dataclasses
import functools
import types
import typing
from collections.abc import Mapping
from typing import Any, TypeVar

from capmj.errors import RecordError

__all__ = ["from_plain", "to_plain"]

R = TypeVar("R")


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def to_plain(record: Any) -> dict[str, Any]:
    """The JSON-ready dict of a record dataclass (nested records, tuples and mappings converted)."""
    omit: frozenset[str] = getattr(record, "OMIT_IF_NONE", frozenset())
    empty: frozenset[str] = getattr(record, "EMPTY_IF_NONE", frozenset())
    out: dict[str, Any] = {}
    for f in dataclasses.fields(record):
        v = getattr(record, f.name)
        if v is None and f.name in omit:
            continue
        out[f.name] = {} if v is None and f.name in empty else _plain(v)
    return out


def _plain(v: Any) -> Any:
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        return v.to_dict() if hasattr(v, "to_dict") else to_plain(v)
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    if isinstance(v, Mapping):
        return {k: _plain(x) for k, x in v.items()}
    return v


def from_plain(cls: type[R], data: Any, *, strict: bool = True, skip: frozenset[str] = frozenset()) -> R:
    """An instance of the record dataclass ``cls`` from ``data`` (keys in ``skip`` are ignored)."""
    name = cls.__name__
    if not isinstance(data, Mapping):
        raise RecordError(f"{name}: expected an object, got {type(data).__name__}")
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    unknown = sorted(set(data) - set(fields) - skip)
    if unknown and strict:
        raise RecordError(f"{name}: unknown key(s) {', '.join(map(repr, unknown))}")
    omit: frozenset[str] = getattr(cls, "OMIT_IF_NONE", frozenset())
    empty: frozenset[str] = getattr(cls, "EMPTY_IF_NONE", frozenset())
    later: frozenset[str] = getattr(cls, "DEFAULT_IF_MISSING", frozenset())
    hints = _hints(typing.cast(type, cls))
    kwargs: dict[str, Any] = {}
    for key, f in fields.items():
        if key in data:
            value = data[key]
            if key in empty and value == {}:
                value = None
            kwargs[key] = _convert(value, hints[key], f"{name}.{key}", strict)
        elif key in omit:
            kwargs[key] = None
        elif key in later:
            continue  # the field's default
        elif strict or (f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING):
            raise RecordError(f"{name}: missing key {key!r}")
    return cls(**kwargs)


def _convert(value: Any, tp: Any, where: str, strict: bool) -> Any:
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        (inner,) = [a for a in args if a is not type(None)]  # the record types use X | None only
        return _convert(value, inner, where, strict)
    if tp is Any:
        return value
    if tp is float:
        if value is None or (isinstance(value, (int, float)) and not isinstance(value, bool)):
            return value
    elif tp is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    elif tp in (bool, str):
        if isinstance(value, tp):
            return value
    elif origin is tuple:
        if isinstance(value, (list, tuple)):
            inner = args[0] if args else Any
            return tuple(_convert(x, inner, f"{where}[{i}]", strict) for i, x in enumerate(value))
    elif origin in (dict, Mapping, typing.Mapping) or tp in (dict, Mapping):
        if isinstance(value, Mapping):
            inner = args[1] if len(args) == 2 else Any
            return {k: _convert(x, inner, f"{where}[{k!r}]", strict) for k, x in value.items()}
    elif isinstance(tp, type) and dataclasses.is_dataclass(tp):
        return tp.from_dict(value, strict=strict) if hasattr(tp, "from_dict") else from_plain(tp, value, strict=strict)
    else:
        raise RecordError(f"{where}: unsupported annotation {tp!r}")
    raise RecordError(f"{where}: expected {getattr(tp, '__name__', tp)}, got {type(value).__name__} {value!r:.80}")
