"""Layer 3 of the sandbox: read-only library facades, allocation guards and curated builtins.

Plan code never sees a real module: ``np``, ``math``, ``itertools``, ``shapely`` and ``utils`` (the
Ravens pose helpers CapRavens' code calls, :mod:`capmj.agents.sandbox.ravens_utils`) are
:class:`_Facade` namespaces of vetted functions, numpy constructors and ``math`` functions with
huge C loops are size-checked before they run, infinite iterators are bounded, and builtins are
a fresh curated dict per run so tampering cannot leak between runs.  ``np.random`` draws from
the generator the caller passes (the episode's), never from numpy's global state, so the same
code gives the same numbers in every process; ``set``/``frozenset`` are insertion-ordered
(:mod:`capmj.agents.sandbox.ordered`) and ``type(x)`` answers with one argument only.  The builders take the run's
session (:class:`~capmj.agents.sandbox.session.Session`) as a parameter, so this module does
not import the runtime and there is no import cycle.
"""

from __future__ import annotations

import builtins as _builtins_module
import functools
import itertools as _itertools
import math as _math
import operator
import sys
import types
from collections.abc import Callable, Iterator, Mapping
from typing import TYPE_CHECKING, Any

import numpy as _np

from capmj.agents.sandbox.ordered import OrderedFrozenSet, OrderedSet
from capmj.agents.sandbox.ravens_utils import utils_members
from capmj.agents.sandbox.sizes import array_elements, broadcast_elements, capped_text, dot_elements
from capmj.errors import TextBudgetExceeded

if TYPE_CHECKING:
    from capmj.agents.sandbox.session import Session

_SAFE_BUILTINS = (
    "abs", "all", "any", "bool", "chr", "dict", "divmod", "enumerate", "filter", "float",
    "frozenset", "int", "isinstance", "len", "list", "map", "max", "min", "next", "ord",
    "repr", "reversed", "round", "set", "slice", "sorted", "str", "sum", "tuple", "zip",
    "ArithmeticError", "AssertionError", "AttributeError", "Exception", "IndexError",
    "KeyError", "LookupError", "NotImplementedError", "OverflowError", "RecursionError",
    "RuntimeError", "StopIteration", "TypeError", "ValueError", "ZeroDivisionError",
)

# Copy only name and doc onto wrappers: ``functools.wraps`` would also copy a wrapped type's
# ``__dict__`` (descriptors such as ``chain.from_iterable``) into the wrapper function.
wraps = functools.partial(functools.wraps, assigned=("__name__", "__qualname__", "__doc__"),
                           updated=())


# ------------------------------------------------------------------------------------------------
# 3. facades
# ------------------------------------------------------------------------------------------------
class _Facade:
    """A read-only namespace exposing only ``members``; stands in for a module."""

    __slots__ = ("_name", "_members")
    _name: str
    _members: Mapping[str, object]

    def __init__(self, name: str, members: Mapping[str, object]) -> None:
        object.__setattr__(self, "_name", name)
        object.__setattr__(self, "_members", types.MappingProxyType(dict(members)))

    def __getattr__(self, attr: str) -> object:
        try:
            return self._members[attr]
        except KeyError:
            message = f"'{self._name}' has no attribute '{attr}' in the sandbox"
            raise AttributeError(message) from None

    def __setattr__(self, attr: str, value: object) -> None:
        raise AttributeError(f"'{self._name}' is read-only in the sandbox")

    def __delattr__(self, attr: str) -> None:
        raise AttributeError(f"'{self._name}' is read-only in the sandbox")

    def __dir__(self) -> list[str]:
        return sorted(self._members)

    def __repr__(self) -> str:
        return f"<sandbox module {self._name}>"


class _TypeCheck:
    """For ``isinstance(x, np.ndarray)``; not callable, as ``np.ndarray(shape)`` allocates."""

    __slots__ = ("_real", "_name")

    def __init__(self, real: type, name: str) -> None:
        self._real, self._name = real, name

    def __instancecheck__(self, obj: object) -> bool:
        return isinstance(obj, self._real)

    def __eq__(self, other: object) -> bool:  # type(x) == np.ndarray, type(a) == type(b)
        return self._real is (other._real if isinstance(other, _TypeCheck) else other)

    def __hash__(self) -> int:
        return hash(self._real)

    def __call__(self, *args: object, **kwargs: object) -> None:
        raise TypeError(f"{self._name} cannot be constructed in the sandbox; use np.array")

    def __repr__(self) -> str:
        return f"<sandbox type {self._name}>"


def _n_elements(shape: object) -> int:
    """Element count of a numpy ``shape`` argument; 0 when malformed (numpy then complains)."""
    try:
        return max(operator.index(shape), 0)  # type: ignore[arg-type]
    except TypeError:
        pass
    if not isinstance(shape, (tuple, list)):
        return 0
    n = 1
    for dim in shape:
        try:
            n *= max(operator.index(dim), 0)
        except TypeError:
            return 0
    return n


def _arange_len(*args: Any, **kwargs: Any) -> int:
    values = dict(zip(("start", "stop", "step"), args if len(args) != 1 else (0, args[0])))
    values.update({k: kwargs[k] for k in ("start", "stop", "step") if k in kwargs})
    start, stop, step = values.get("start", 0), values.get("stop"), values.get("step", 1)
    if stop is None:
        start, stop = 0, start
    span = (float(stop) - float(start)) / float(step)
    return int(_math.ceil(span)) if _math.isfinite(span) else sys.maxsize


def _size(a: Any) -> int:
    """Elements of ``a`` as an array, without making one of a nested list (see :mod:`.sizes`)."""
    return array_elements(a, sys.maxsize) if isinstance(a, (list, tuple, _np.ndarray)) else 1


def _repeat_len(a: Any, repeats: Any, *args: Any, **kwargs: Any) -> int:
    most = max(repeats) if isinstance(repeats, (list, tuple)) and repeats else repeats
    return _size(a) * (int(_np.max(most)) if _size(most) else 0)


def _like_len(a: Any, *args: Any, shape: Any = None, **kwargs: Any) -> int:
    return _n_elements(shape) if shape is not None else _size(a)


_BinaryOp = Callable[[Any, Any], Any]


def checked_op(check: _BinaryOp, op: _BinaryOp) -> _BinaryOp:
    def apply(a: Any, b: Any) -> Any:
        return op(a, check(a, b))

    return apply


def growth(obj: Any, name: str, args: tuple[Any, ...], kwargs: dict[str, Any]) -> int:
    """Elements ``obj.name(*args, **kwargs)`` would produce (arrays and strings only)."""
    if isinstance(obj, _np.ndarray):
        if name == "repeat":
            return _repeat_len(obj, *args, **kwargs)
        if name == "resize":
            return _n_elements(args[0] if len(args) == 1 else args)
        if name == "dot":
            return dot_elements(obj, args[0] if args else kwargs["b"])
        if name == "clip":
            return broadcast_elements(obj, *args, *kwargs.values())
        return 0
    if name == "expandtabs":
        return len(obj) * max(operator.index(args[0] if args else kwargs.get("tabsize", 8)), 1)
    if name == "replace":
        old, new = args[0], args[1]
        count = args[2] if len(args) > 2 else kwargs.get("count", -1)
        hits = obj.count(old) if old else len(obj) + 1
        hits = hits if count < 0 else min(hits, count)
        return len(obj) + hits * max(len(new) - len(old), 0)
    if name in ("ljust", "rjust", "center", "zfill"):
        return operator.index(args[0] if args else kwargs.get("width", 0))
    return 0


_NP_ALLOCATORS: dict[str, Callable[..., int]] = {
    "zeros": lambda shape, *a, **k: _n_elements(shape),
    "ones": lambda shape, *a, **k: _n_elements(shape),
    "empty": lambda shape, *a, **k: _n_elements(shape),
    "full": lambda shape, *a, **k: _n_elements(shape),
    "eye": lambda N, M=None, *a, **k: operator.index(N) * operator.index(N if M is None else M),
    "identity": lambda n, *a, **k: operator.index(n) ** 2,
    "arange": _arange_len,
    "linspace": lambda start, stop, num=50, *a, **k: operator.index(num),
    "tile": lambda A, reps, **k: _size(A) * _n_elements(reps),
    "repeat": _repeat_len,
    "zeros_like": _like_len,
    "ones_like": _like_len,
    "full_like": _like_len,
}
def _array_len(obj: Any, dtype: Any = None, *args: Any, **kwargs: Any) -> int:
    """``np.array(obj, dtype)``: the elements of ``obj`` (eight-byte words: wide strings count more),
    times the words of one ``dtype`` item when one is given."""
    dtype = kwargs.get("dtype", dtype)
    n = _size(obj)
    if dtype is not None:
        try:
            n *= max(1, -(-_np.dtype(dtype).itemsize // 8))
        except TypeError:
            pass  # not a dtype: numpy raises its own error
    return n


def _stacked_len(arrays: Any, *args: Any, **kwargs: Any) -> int:
    """``np.concatenate`` / ``stack`` / ...: every element of every array listed (an array listed
    many times counts each time)."""
    return _size(arrays)


def _broadcast_len(*args: Any, **kwargs: Any) -> int:
    """An element-wise function of its array arguments: their broadcast result."""
    operands = [a for a in (*args, *kwargs.values()) if isinstance(a, (list, tuple, _np.ndarray, _np.generic))]
    return broadcast_elements(*operands) if operands else 1


def _where_len(condition: Any, *args: Any, **kwargs: Any) -> int:
    if not args:  # np.where(condition): the indices of the true elements, one array per axis
        return _size(condition) * max(1, _np.ndim(condition) if isinstance(condition, _np.ndarray) else 1)
    return broadcast_elements(condition, *args)


def _dot_len(a: Any, b: Any, *args: Any, **kwargs: Any) -> int:
    return dot_elements(a, b)


def _interp_len(x: Any, *args: Any, **kwargs: Any) -> int:
    return _size(x)


_NP_SIZED: dict[str, Callable[..., int]] = {
    "array": _array_len, "asarray": _array_len,
    "concatenate": _stacked_len, "stack": _stacked_len, "vstack": _stacked_len, "hstack": _stacked_len,
    "column_stack": _stacked_len,
    "arctan2": _broadcast_len, "mod": _broadcast_len, "maximum": _broadcast_len, "minimum": _broadcast_len,
    "hypot": _broadcast_len, "isclose": _broadcast_len, "allclose": _broadcast_len, "clip": _broadcast_len,
    "cross": _broadcast_len, "where": _where_len, "dot": _dot_len, "interp": _interp_len,
}
"""numpy functions whose result can be larger than any one argument, by the size of that result;
every other function of the facade makes at most arrays of its arguments' sizes."""
_NP_WHOLE_FIRST = frozenset({"array", "asarray", "concatenate", "stack", "vstack", "hstack", "column_stack"})
"""Functions whose size above already counts everything made of their first argument."""
_NP_PLAIN = (
    "mean", "median", "std", "var", "sum", "prod", "min", "max", "argmin",
    "argmax", "argsort", "sort", "abs", "absolute", "sqrt", "square", "exp", "log", "sin", "cos",
    "tan", "arctan", "arcsin", "arccos", "deg2rad", "rad2deg", "radians", "degrees",
    "round", "floor", "ceil", "sign", "all", "any", "unique",
    "diff", "cumsum", "reshape", "transpose", "expand_dims",
    "squeeze", "flip", "isnan", "isfinite", "nonzero", "argwhere", "count_nonzero",
)
"""numpy functions whose result is at most as large as their arguments as arrays."""
_NP_SCALAR_TYPES = ("float32", "float64", "int32", "int64", "bool_")
_NP_CONSTANTS = ("pi", "inf", "nan", "e", "newaxis")
_MATH_INT_CAPS = {"factorial": 20_000, "comb": 100_000, "perm": 100_000}
_ITERTOOLS = (
    "permutations", "combinations", "combinations_with_replacement", "product", "islice",
    "cycle", "count", "repeat", "accumulate", "groupby", "zip_longest", "pairwise", "starmap",
    "takewhile", "dropwhile", "compress", "filterfalse",
)


def _guarded(session: Session, fn: Callable[..., Any], size: Callable[..., int] | None,
             label: str, *, whole_first: bool = False) -> Callable[..., Any]:
    """``fn`` that first counts the arrays numpy makes of its nested-list arguments (but the first
    with ``whole_first``: ``size`` counts it) and the result ``size(*args, **kwargs)`` says it
    makes (None: no result larger than its arguments)."""
    @wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        session.check_inputs((*args[1 if whole_first else 0:], *kwargs.values()), label)
        try:
            n = size(*args, **kwargs) if size is not None else 0
        except (TypeError, ValueError, OverflowError, ZeroDivisionError, IndexError, KeyError):
            n = 0  # malformed arguments: the real function raises its own error
        session.allocate(n, label)
        return fn(*args, **kwargs)

    return wrapper


class _ScalarType(_TypeCheck):
    """``np.float64`` and its kin: ``isinstance``, ``dtype=`` and comparison as the real type, and a
    call (``np.float64([[...]])`` makes an array) counted like ``np.array``."""

    __slots__ = ("_call", "dtype")

    def __init__(self, real: type, name: str, call: Callable[..., Any]) -> None:
        super().__init__(real, name)
        self._call, self.dtype = call, _np.dtype(real)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:  # type: ignore[override]
        return self._call(*args, **kwargs)


def _size_kw(size: Any = None, **_: Any) -> int:
    return 1 if size is None else _n_elements(size)


def _random_facade(session: Session, rng: _np.random.Generator) -> _Facade:
    """``np.random`` over ``rng``: the legacy names LLM code writes, mapped onto the Generator.

    ``seed`` is accepted and ignored and ``default_rng`` returns this facade: draws always come
    from the episode's generator, so a replayed completion draws the same numbers.
    """
    def dims(*d: Any) -> Any:
        return tuple(d) if d else None

    real: dict[str, tuple[Callable[..., Any], Callable[..., int]]] = {
        "rand": (lambda *d: rng.random(dims(*d)), lambda *d: _n_elements(tuple(d))),
        "randn": (lambda *d: rng.standard_normal(dims(*d)), lambda *d: _n_elements(tuple(d))),
        "random": (lambda size=None: rng.random(size), _size_kw),
        "randint": (lambda low, high=None, size=None, dtype=int: rng.integers(low, high, size, dtype),
                    lambda low, high=None, size=None, **k: _size_kw(size)),
        "integers": (lambda low, high=None, size=None, dtype=_np.int64, endpoint=False:
                     rng.integers(low, high, size, dtype, endpoint),
                     lambda low, high=None, size=None, **k: _size_kw(size)),
        "uniform": (lambda low=0.0, high=1.0, size=None: rng.uniform(low, high, size),
                    lambda low=0.0, high=1.0, size=None: _size_kw(size)),
        "normal": (lambda loc=0.0, scale=1.0, size=None: rng.normal(loc, scale, size),
                   lambda loc=0.0, scale=1.0, size=None: _size_kw(size)),
        "standard_normal": (lambda size=None: rng.standard_normal(size), _size_kw),
        "choice": (lambda a, size=None, replace=True, p=None: rng.choice(a, size, replace, p),
                   lambda a, size=None, **k: max(_size_kw(size), operator.index(a)
                                                if isinstance(a, int) else 0)),
        "permutation": (lambda x: rng.permutation(x),
                        lambda x: operator.index(x) if isinstance(x, int) else _size(x)),
        "shuffle": (lambda x: rng.shuffle(x), lambda x: 0),
    }
    members: dict[str, object] = {name: _guarded(session, fn, size, f"np.random.{name}()")
                                  for name, (fn, size) in real.items()}
    for alias, name in (("random_sample", "random"), ("sample", "random"), ("ranf", "random")):
        members[alias] = members[name]
    members["seed"] = lambda *args, **kwargs: None
    this: list[_Facade] = []
    members["default_rng"] = lambda *args, **kwargs: this[0]
    this.append(_Facade("np.random", members))
    return this[0]


def _int_capped(session: Session, fn: Callable[..., Any], cap: int,
                label: str) -> Callable[..., Any]:
    """``fn`` refusing integer arguments above ``cap`` (its C loop could run for hours)."""
    @wraps(fn)
    def wrapper(*args: Any) -> Any:
        if any(isinstance(a, int) and a > cap for a in args):
            session.abort(f"{label} arguments are limited to {cap}")
        return fn(*args)

    return wrapper


@functools.cache
def _numpy_text_ready() -> None:
    """Make numpy set up its array printing now, outside sandboxed frames: the first ``str`` or
    ``repr`` of an array imports numpy's printing code, and an import from plan code (an
    f-string with an array in it) finds no ``__import__`` in the curated builtins and fails."""
    str(_np.zeros(1))
    repr(_np.zeros(1))


def _facades(session: Session, rng: _np.random.Generator) -> dict[str, object]:
    """Fresh facades for one run (they close over the run's budget and random generator)."""
    _numpy_text_ready()
    import shapely.affinity
    import shapely.geometry

    np_members: dict[str, object] = {name: getattr(_np, name) for name in _NP_CONSTANTS}
    for name in _NP_PLAIN:
        np_members[name] = _guarded(session, getattr(_np, name), None, f"np.{name}()")
    for name, size in {**_NP_SIZED, **_NP_ALLOCATORS}.items():
        np_members[name] = _guarded(session, getattr(_np, name), size, f"np.{name}()",
                                    whole_first=name in _NP_WHOLE_FIRST)
    for name in _NP_SCALAR_TYPES:
        real = getattr(_np, name)
        np_members[name] = _ScalarType(real, f"np.{name}", _guarded(session, real, _array_len, f"np.{name}()",
                                                                     whole_first=True))
    np_members["ndarray"] = _TypeCheck(_np.ndarray, "np.ndarray")
    np_members["random"] = _random_facade(session, rng)
    np_members["linalg"] = _Facade("np.linalg", {n: _guarded(session, getattr(_np.linalg, n), None, f"np.linalg.{n}()")
                                                for n in ("norm", "inv", "det", "solve")})

    geometry = {n: getattr(shapely.geometry, n)
                for n in _GEOMETRY_NAMES}
    affinity = {n: getattr(shapely.affinity, n) for n in _AFFINITY_NAMES}
    shapely_facade = _Facade("shapely", {
        "geometry": _Facade("shapely.geometry", geometry),
        "affinity": _Facade("shapely.affinity", affinity),
        **geometry,
    })

    math_members: dict[str, object] = {n: getattr(_math, n) for n in dir(_math)
                                       if not n.startswith("_")}
    for name, cap in _MATH_INT_CAPS.items():
        math_members[name] = _int_capped(session, getattr(_math, name), cap, f"math.{name}()")

    def iterator(name: str) -> Callable[..., Iterator[Any]]:
        real = getattr(_itertools, name)

        @wraps(real)
        def make(*args: Any, **kwargs: Any) -> Iterator[Any]:
            return session.bounded(real(*args, **kwargs), f"itertools.{name}()")

        return make

    iter_members: dict[str, object] = {name: iterator(name) for name in _ITERTOOLS}
    chain = iterator("chain")
    chain.from_iterable = lambda it: session.bounded(  # type: ignore[attr-defined]
        _itertools.chain.from_iterable(it), "itertools.chain()")
    iter_members["chain"] = chain

    return {
        "np": _Facade("np", np_members),
        "math": _Facade("math", math_members),
        "itertools": _Facade("itertools", iter_members),
        "shapely": shapely_facade,
        "utils": _Facade("utils", utils_members()),
        **geometry,
        **affinity,
    }


_GEOMETRY_NAMES = ("Point", "Polygon", "LineString", "MultiPoint", "MultiPolygon", "box")
_AFFINITY_NAMES = ("rotate", "translate", "scale")

PROVIDED_NAMES: frozenset[str] = frozenset(
    ("np", "math", "itertools", "shapely", "utils", "print", "range", "type", "True", "False", "None")
    + _GEOMETRY_NAMES + _AFFINITY_NAMES + _SAFE_BUILTINS
)
"""Every global name ``run_code`` provides besides the caller's ``env`` (facades, shapely
shortcuts, curated builtins): code using only these and ``env`` needs nothing synthesised."""


def _builtins(session: Session, output: list[str] | None) -> dict[str, object]:
    """A fresh curated builtins dict: tampering in one run cannot reach the next."""
    table: dict[str, object] = {n: getattr(_builtins_module, n) for n in _SAFE_BUILTINS}
    printed = [0]
    cap = session.budget.max_text_chars

    def captured_print(*args: object, sep: object = " ", end: object = "\n",
                       file: object = None, flush: bool = False) -> None:
        if output is None:
            return  # nobody reads it: no text is made
        pieces: list[str] = []
        room = cap - printed[0]
        for a in (" " if sep is None else sep, "" if end in (None, "\n") else end, *args):
            piece = capped_text(a, room)
            if piece is None or (room := room - len(piece) * (max(len(args) - 1, 0) if not pieces else 1)) < 0:
                session.abort(f"print() output would pass {cap} characters of text in this run (max_text_chars)",
                              TextBudgetExceeded)
            pieces.append(str(piece))
        separator, ending, *values = pieces
        text = separator.join(values) + ending
        printed[0] += len(text)
        output.append(text)

    table["print"] = captured_print
    table["repr"] = session.checked_repr
    table["range"] = session.capped_range
    table["set"], table["frozenset"] = OrderedSet, OrderedFrozenSet
    table["type"] = _safe_type(table)
    return table


_NP_TYPES = frozenset(getattr(_np, n) for n in ("float32", "float64", "int32", "int64", "bool_"))


def _safe_type(table: Mapping[str, object]) -> Callable[[object], object]:
    """One-argument ``type``: a real type only for builtins and numpy scalar types the sandbox
    already exposes, a non-callable stand-in (comparable, usable in ``isinstance``) otherwise."""
    exposed = {v for v in table.values() if isinstance(v, type)} | _NP_TYPES

    def type_(*args: object) -> object:
        if len(args) != 1:
            raise TypeError("type() takes exactly one argument in the sandbox (it cannot create classes)")
        kind = type(args[0])
        if issubclass(kind, float) and kind.__module__.startswith("capmj."):
            kind = float  # the API's Coordinate is a float to plan code, type(x) == float included
        if kind in exposed:
            return kind
        name = "np.ndarray" if kind is _np.ndarray else f"{kind.__module__}.{kind.__qualname__}"
        return _TypeCheck(kind, name)

    type_.__name__ = type_.__qualname__ = "type"
    return type_


def run_namespace(session: Session, output: list[str] | None, rng: _np.random.Generator) -> dict[str, object]:
    """The globals a run starts with: fresh curated builtins (``print`` appends to ``output``), the
    run's module name and fresh facades over ``rng``."""
    namespace: dict[str, object] = {"__builtins__": _builtins(session, output), "__name__": "__llm_plan__"}
    namespace.update(_facades(session, rng))
    return namespace


def is_api_function(value: object) -> bool:
    """Whether a value of the caller's ``env`` is a function whose calls count as API calls: callable,
    and not a type, a facade or a type check (which only stand for a module or a class)."""
    return callable(value) and not isinstance(value, (type, _Facade, _TypeCheck))
