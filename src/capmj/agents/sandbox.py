"""The only way capmj runs LLM-written code: a checked, rewritten, budgeted ``exec``.

Why this design (and not just ``exec`` with empty builtins): LLM code is untrusted in two ways.
It can reach the interpreter (``().__class__.__bases__``, ``np.load``, frames) and it can
accidentally never finish or allocate the machine to death (``while True``, ``[0] * 10**10``).
So each run goes through four layers:

1. **Static allow-list** (:func:`check_code`): only plain statements/expressions parse through;
   imports, classes, ``global``, ``with``, ``yield``/``async``, ``finally``, dunder names, any
   ``_private`` attribute and known dangerous names/attributes are rejected with their line.
2. **Rewrite**: ``*``, ``**``, ``<<`` and ``+`` (and their augmented forms) become calls of
   guards that refuse results above ``max_elements`` elements / 10**6 bits *before* computing
   them; every ``while`` body ticks the clock; a few growing methods (``arr.repeat``,
   ``s.ljust``, ``sep.join`` ...) are checked.  Guard names start with ``__`` which user code
   can never write, because the check runs first.
3. **Facades, not modules**: ``np``, ``math``, ``itertools``, ``shapely`` are read-only
   namespaces of vetted functions; allocating numpy constructors and infinite iterators are
   size-capped.  Builtins are a fresh curated dict each run, so nothing leaks between runs.
4. **Budgets at run time**: a ``sys.settrace`` tracer (only sandbox frames) enforces wall time
   and optional executed-line counts; env functions count API calls.  Violations raise an
   internal ``BaseException`` that ``except Exception`` cannot swallow.

Everything surfaces as :class:`PlanError` / :class:`BudgetExceeded` ("ErrorClass: message",
1-based line in the submitted code).  Known gaps, on purpose: C-level work that is slow but
bounded (big numpy ops, ``shapely`` buffers with huge resolutions, format widths like
``f"{x:>1000000000}"``) is not interruptible; run plans in a subprocess for hard isolation.
"""

from __future__ import annotations

import ast
import builtins as _builtins_module
import copy
import functools
import itertools as _itertools
import math as _math
import operator
import re
import sys
import textwrap
import time
import types
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as _np

from capmj.errors import BudgetExceeded, ConfigError, PlanError

__all__ = ["FORBIDDEN_ATTRIBUTES", "FORBIDDEN_NAMES", "SandboxBudget", "check_code",
           "extract_code", "run_code"]

MAX_INT_BITS = 1_000_000
"""Largest integer result (in bits) that ``**``, ``<<`` and ``*`` may produce."""

_MAX_PRINT_CHARS = 1_000_000

FORBIDDEN_NAMES = frozenset({
    "exec", "eval", "compile", "open", "globals", "locals", "vars", "dir", "getattr", "setattr",
    "delattr", "hasattr", "input", "breakpoint", "help", "memoryview", "type", "object",
    "super", "classmethod", "staticmethod", "property", "exit", "quit", "BaseException",
})
"""Rejected wherever the code reads them without binding them itself (none is a builtin here)."""

FORBIDDEN_ATTRIBUTES = frozenset({
    "tofile", "dump", "dumps", "ctypes", "load", "loads", "save", "savez", "savez_compressed",
    "savetxt", "loadtxt", "genfromtxt", "fromfile", "memmap", "gi_frame", "gi_code", "ag_frame",
    "cr_frame", "f_globals", "f_locals", "f_builtins", "f_back", "f_code", "f_trace",
    "tb_frame", "tb_next", "mro",
})
"""Rejected on any object: file I/O, pickling, raw memory and frame access."""

_SAFE_BUILTINS = (
    "abs", "all", "any", "bool", "chr", "dict", "divmod", "enumerate", "filter", "float",
    "frozenset", "int", "isinstance", "len", "list", "map", "max", "min", "next", "ord",
    "repr", "reversed", "round", "set", "slice", "sorted", "str", "sum", "tuple", "zip",
    "ArithmeticError", "AssertionError", "AttributeError", "Exception", "IndexError",
    "KeyError", "LookupError", "NotImplementedError", "OverflowError", "RecursionError",
    "RuntimeError", "StopIteration", "TypeError", "ValueError", "ZeroDivisionError",
)

_ALLOWED_NODES: tuple[type[ast.AST], ...] = (
    ast.Module, ast.Expr, ast.Assign, ast.AugAssign, ast.AnnAssign, ast.For, ast.While, ast.If,
    ast.FunctionDef, ast.Return, ast.Pass, ast.Break, ast.Continue, ast.Try, ast.ExceptHandler,
    ast.Raise, ast.Assert, ast.Delete, ast.ListComp, ast.SetComp, ast.DictComp,
    ast.GeneratorExp, ast.comprehension, ast.BinOp, ast.UnaryOp, ast.BoolOp, ast.Compare,
    ast.Call, ast.Attribute, ast.Subscript, ast.Slice, ast.Name, ast.Constant, ast.List,
    ast.Tuple, ast.Dict, ast.Set, ast.IfExp, ast.Lambda, ast.JoinedStr, ast.FormattedValue,
    ast.Starred, ast.NamedExpr, ast.keyword, ast.arguments, ast.arg, ast.Load, ast.Store,
    ast.Del, ast.operator, ast.unaryop, ast.boolop, ast.cmpop,
)

_WHY_NOT = {
    ast.Import: "import statements are not allowed; np, math, itertools and shapely are "
                "already available",
    ast.ImportFrom: "import statements are not allowed; np, math, itertools and shapely are "
                    "already available",
    ast.ClassDef: "class definitions are not allowed; use functions and dicts",
    ast.Global: "global statements are not allowed; return values instead",
    ast.Nonlocal: "nonlocal statements are not allowed; return values instead",
    ast.With: "with statements are not allowed",
    ast.Yield: "generators (yield) are not allowed",
    ast.YieldFrom: "generators (yield) are not allowed",
}

# Methods whose result can be far larger than their inputs; loads of these attributes are routed
# through a checker.
_GROWING_METHODS = frozenset({"repeat", "resize", "ljust", "rjust", "center", "zfill",
                              "expandtabs", "replace", "join"})
_SEQUENCES = (str, bytes, bytearray, list, tuple)

# Copy only name and doc onto wrappers: ``functools.wraps`` would also copy a wrapped type's
# ``__dict__`` (descriptors such as ``chain.from_iterable``) into the wrapper function.
_wraps = functools.partial(functools.wraps, assigned=("__name__", "__qualname__", "__doc__"),
                           updated=())


@dataclass(frozen=True)
class SandboxBudget:
    """Resources one run may use.  ``max_elements`` caps any single allocation it can foresee."""

    wall_s: float = 30.0
    max_api_calls: int = 500
    max_elements: int = 10_000_000
    max_lines: int | None = None

    def __post_init__(self) -> None:
        if not self.wall_s > 0 or self.max_api_calls < 0 or self.max_elements <= 0:
            raise ConfigError(f"invalid SandboxBudget {self}: wall_s and max_elements must be "
                              "positive, max_api_calls >= 0")
        if self.max_lines is not None and self.max_lines <= 0:
            raise ConfigError(f"SandboxBudget.max_lines must be positive or None, not "
                              f"{self.max_lines}")


class _Abort(BaseException):
    """A budget violation; a BaseException so sandboxed ``except Exception`` cannot catch it."""


# ------------------------------------------------------------------------------------------------
# 1. static check
# ------------------------------------------------------------------------------------------------
def _bound_names(tree: ast.AST) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and not isinstance(node.ctx, ast.Load):
            names.add(node.id)
        elif isinstance(node, ast.arg):
            names.add(node.arg)
        elif isinstance(node, (ast.FunctionDef, ast.ExceptHandler)) and node.name:
            names.add(node.name)
    return names


def _check_node(node: ast.AST, line: int | None, bound: set[str], code: str) -> None:
    line = getattr(node, "lineno", None) or line

    def reject(message: str) -> None:
        raise PlanError(f"SandboxViolation: {message}", line=line, code=code)

    if not isinstance(node, _ALLOWED_NODES):
        kind = type(node)
        reject(_WHY_NOT.get(kind, f"{kind.__name__} is not allowed in plan code"))
    identifiers: list[str] = []
    if isinstance(node, ast.Name):
        identifiers.append(node.id)
        if node.id in FORBIDDEN_NAMES and node.id not in bound:
            reject(f"the name '{node.id}' is not available")
    elif isinstance(node, ast.Attribute):
        if node.attr.startswith("_"):
            reject(f"private attribute '.{node.attr}' is not allowed")
        if node.attr in FORBIDDEN_ATTRIBUTES:
            reject(f"attribute '.{node.attr}' is not allowed")
    elif isinstance(node, ast.keyword) and node.arg is not None:
        identifiers.append(node.arg)
    elif isinstance(node, ast.arg):
        identifiers.append(node.arg)
    elif isinstance(node, (ast.FunctionDef, ast.ExceptHandler)) and node.name:
        identifiers.append(node.name)
    elif isinstance(node, ast.Try) and node.finalbody:
        reject("try/finally is not allowed; use try/except")
    for name in identifiers:
        if name.startswith("__"):
            reject(f"the name '{name}' is not allowed (names may not start with '__')")
    for child in ast.iter_child_nodes(node):
        _check_node(child, line, bound, code)


def check_code(code: str) -> ast.Module:
    """Parse and allow-list-check ``code``; the AST, or PlanError naming the offending line."""
    if not isinstance(code, str):
        raise PlanError(f"TypeError: plan code must be str, not {type(code).__name__}")
    try:
        tree = ast.parse(code, mode="exec")
    except SyntaxError as exc:
        raise PlanError(f"SyntaxError: {exc.msg}", line=exc.lineno, code=code) from None
    except (ValueError, RecursionError, MemoryError) as exc:
        raise PlanError(f"SyntaxError: {exc}", code=code) from None
    try:
        _check_node(tree, None, _bound_names(tree), code)
    except RecursionError:
        raise PlanError("SandboxViolation: code is nested too deeply", code=code) from None
    return tree


# ------------------------------------------------------------------------------------------------
# 2. rewrite
# ------------------------------------------------------------------------------------------------
_BINOP_GUARDS = {ast.Mult: "__cap_mul", ast.Pow: "__cap_pow", ast.LShift: "__cap_lshift",
                 ast.Add: "__cap_add"}


def _helper_call(name: str, args: list[ast.expr], like: ast.AST) -> ast.Call:
    call = ast.Call(func=ast.Name(id=name, ctx=ast.Load()), args=args, keywords=[])
    return ast.copy_location(call, like)


def _helper_statement(name: str, like: ast.AST) -> ast.Expr:
    return ast.copy_location(ast.Expr(_helper_call(name, [], like)), like)


class _Rewriter(ast.NodeTransformer):
    """Routes resource-hungry operations of checked code through the session's guards."""

    def visit_BinOp(self, node: ast.BinOp) -> ast.AST:
        self.generic_visit(node)
        guard = _BINOP_GUARDS.get(type(node.op))
        return _helper_call(guard, [node.left, node.right], node) if guard else node

    def visit_AugAssign(self, node: ast.AugAssign) -> ast.AST:
        # Re-reading the target is only safe when that has no side effects (no calls in it).
        pure = not any(isinstance(n, ast.Call) for n in ast.walk(node.target))
        self.generic_visit(node)
        guard = _BINOP_GUARDS.get(type(node.op))
        if guard and pure:
            current = copy.deepcopy(node.target)
            current.ctx = ast.Load()  # type: ignore[attr-defined]
            # In place (keeps list/ndarray identity): x op= check(x, y) returns y unchanged.
            node.value = _helper_call(guard + "_check", [current, node.value], node)
        return node

    def visit_Attribute(self, node: ast.Attribute) -> ast.AST:
        self.generic_visit(node)
        if isinstance(node.ctx, ast.Load) and node.attr in _GROWING_METHODS:
            return _helper_call("__cap_attr", [node.value, ast.Constant(node.attr)], node)
        return node

    def visit_While(self, node: ast.While) -> ast.AST:
        self.generic_visit(node)
        # ``while True: pass`` emits no per-iteration line events: tick explicitly.
        node.body.insert(0, _helper_statement("__cap_tick", node))
        return node

    def visit_ExceptHandler(self, node: ast.ExceptHandler) -> ast.AST:
        self.generic_visit(node)
        if node.type is None:  # bare except: would catch our aborts
            node.type = ast.copy_location(ast.Name(id="__cap_Exception", ctx=ast.Load()), node)
        # A tracer that raised (e.g. RecursionError at the recursion limit) is switched off by
        # CPython; re-arm it whenever the code swallows an exception.
        node.body.insert(0, _helper_statement("__cap_rearm", node))
        return node


# ------------------------------------------------------------------------------------------------
# 3. facades
# ------------------------------------------------------------------------------------------------
class _Facade:
    """A read-only namespace exposing only ``members``; stands in for a module."""

    __slots__ = ("_name", "_members")

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


def _repeat_len(a: Any, repeats: Any, *args: Any, **kwargs: Any) -> int:
    return int(_np.size(a)) * (int(_np.max(repeats)) if _np.size(repeats) else 0)


def _like_len(a: Any, *args: Any, shape: Any = None, **kwargs: Any) -> int:
    return _n_elements(shape) if shape is not None else int(_np.size(a))


_BinaryOp = Callable[[Any, Any], Any]


def _checked_op(check: _BinaryOp, op: _BinaryOp) -> _BinaryOp:
    def apply(a: Any, b: Any) -> Any:
        return op(a, check(a, b))

    return apply


def _growth(obj: Any, name: str, args: tuple[Any, ...], kwargs: dict[str, Any]) -> int:
    """Elements ``obj.name(*args, **kwargs)`` would produce (arrays and strings only)."""
    if isinstance(obj, _np.ndarray):
        if name == "repeat":
            return _repeat_len(obj, *args, **kwargs)
        if name == "resize":
            return _n_elements(args[0] if len(args) == 1 else args)
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
    "tile": lambda A, reps, **k: int(_np.size(A)) * _n_elements(reps),
    "repeat": _repeat_len,
    "zeros_like": _like_len,
    "ones_like": _like_len,
    "full_like": _like_len,
}
_NP_PLAIN = (
    "array", "asarray", "mean", "median", "std", "var", "sum", "prod", "min", "max", "argmin",
    "argmax", "argsort", "sort", "abs", "absolute", "sqrt", "square", "exp", "log", "sin", "cos",
    "tan", "arctan", "arctan2", "arcsin", "arccos", "deg2rad", "rad2deg", "radians", "degrees",
    "clip", "round", "floor", "ceil", "sign", "mod", "concatenate", "stack", "vstack", "hstack",
    "column_stack", "where", "dot", "cross", "isclose", "allclose", "all", "any", "unique",
    "diff", "cumsum", "maximum", "minimum", "hypot", "reshape", "transpose", "expand_dims",
    "squeeze", "flip", "isnan", "isfinite", "nonzero", "argwhere", "count_nonzero", "interp",
    "float32", "float64", "int32", "int64", "bool_", "pi", "inf", "nan", "e", "newaxis",
)
_MATH_INT_CAPS = {"factorial": 20_000, "comb": 100_000, "perm": 100_000}
_ITERTOOLS = (
    "permutations", "combinations", "combinations_with_replacement", "product", "islice",
    "cycle", "count", "repeat", "accumulate", "groupby", "zip_longest", "pairwise", "starmap",
    "takewhile", "dropwhile", "compress", "filterfalse",
)


# ------------------------------------------------------------------------------------------------
# 4. one run: budgets, guards, tracer
# ------------------------------------------------------------------------------------------------
class _Session:
    """Mutable state of one ``run_code`` call (and of later calls of the functions it defined)."""

    def __init__(self, budget: SandboxBudget, filename: str, code: str) -> None:
        self.budget, self.filename, self.code = budget, filename, code
        self.api_calls = 0
        self.lines = 0
        self.ticks = 0
        self.deadline = float("inf")
        self.active = False
        self.aborted: str | None = None

    # -- budgets ---------------------------------------------------------------------------
    def abort(self, message: str) -> None:
        self.aborted = self.aborted or message
        raise _Abort(self.aborted)

    def check_time(self) -> None:
        if self.aborted:
            raise _Abort(self.aborted)
        if time.monotonic() > self.deadline:
            self.abort(f"wall time budget of {self.budget.wall_s:g} s exceeded")

    def limit(self, n: int, what: str) -> None:
        if n > self.budget.max_elements:
            self.abort(f"{what} would create {n} elements (max_elements="
                       f"{self.budget.max_elements})")

    def global_trace(self, frame: types.FrameType, event: str, arg: object) -> Any:
        if frame.f_code.co_filename != self.filename:
            return None  # library frames run untraced (fast); their callers are traced
        self.check_time()
        return self.local_trace

    def local_trace(self, frame: types.FrameType, event: str, arg: object) -> Any:
        if event == "line":
            self.lines += 1
            if self.budget.max_lines is not None and self.lines > self.budget.max_lines:
                self.abort(f"executed-line budget of {self.budget.max_lines} exceeded")
            if not self.lines & 63:
                self.check_time()
        return self.local_trace

    # -- helpers the rewritten code calls ---------------------------------------------------
    def tick(self) -> None:
        self.ticks += 1
        if not self.ticks & 15:
            self.check_time()

    def rearm(self) -> None:
        self.check_time()
        if sys.gettrace() is None:
            sys.settrace(self.global_trace)
            frame: types.FrameType | None = sys._getframe(1)
            while frame is not None:
                if frame.f_code.co_filename == self.filename:
                    frame.f_trace = self.local_trace
                frame = frame.f_back

    def check_mul(self, a: Any, b: Any) -> Any:
        for seq, count in ((a, b), (b, a)):
            if isinstance(seq, _SEQUENCES) and not isinstance(count, (_SEQUENCES, _np.ndarray)):
                try:
                    self.limit(len(seq) * operator.index(count), "sequence repetition")
                except TypeError:
                    pass
                return b
        if isinstance(a, int) and isinstance(b, int) and (
                a.bit_length() + b.bit_length() > MAX_INT_BITS):
            self.abort(f"integer product would exceed {MAX_INT_BITS} bits")
        return b

    def check_pow(self, a: Any, b: Any) -> Any:
        if isinstance(a, int) and isinstance(b, int) and b > 0 and abs(a) > 1:
            if b * abs(a).bit_length() > MAX_INT_BITS:
                self.abort(f"integer power would exceed {MAX_INT_BITS} bits")
        return b

    def check_lshift(self, a: Any, b: Any) -> Any:
        if isinstance(a, int) and isinstance(b, int) and a and a.bit_length() + b > MAX_INT_BITS:
            self.abort(f"integer shift would exceed {MAX_INT_BITS} bits")
        return b

    def check_add(self, a: Any, b: Any) -> Any:
        if isinstance(a, _SEQUENCES) and isinstance(b, _SEQUENCES):
            self.limit(len(a) + len(b), "concatenation")
        return b

    def helpers(self) -> dict[str, object]:
        ops = {"mul": operator.mul, "pow": operator.pow, "lshift": operator.lshift,
               "add": operator.add}
        out: dict[str, object] = {
            "__cap_tick": self.tick, "__cap_rearm": self.rearm, "__cap_attr": self.attribute,
            "__cap_Exception": Exception,
        }
        for name, op in ops.items():
            check = getattr(self, f"check_{name}")
            out[f"__cap_{name}_check"] = check  # for ``x op= y``: returns y after checking
            out[f"__cap_{name}"] = _checked_op(check, op)
        return out

    def attribute(self, obj: Any, name: str) -> Any:
        """``obj.name`` for a growing method, size-checked when ``obj`` is an array or string."""
        value = getattr(obj, name)
        if not isinstance(obj, (_np.ndarray, str, bytes, bytearray)) or not callable(value):
            return value

        @_wraps(value)
        def checked(*args: Any, **kwargs: Any) -> Any:
            if name == "join" and args:
                items = list(args[0])
                total = sum(len(i) for i in items if isinstance(i, _SEQUENCES))
                self.limit(total + len(obj) * max(len(items) - 1, 0), f".{name}()")
                return value(items, *args[1:], **kwargs)
            try:
                n = _growth(obj, name, args, kwargs)
            except (TypeError, ValueError, IndexError, KeyError):
                n = 0  # malformed call: let the real method raise its own error
            self.limit(n, f".{name}()")
            return value(*args, **kwargs)

        return checked

    def count_calls(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        @_wraps(fn)
        def counted(*args: Any, **kwargs: Any) -> Any:
            self.check_time()
            self.api_calls += 1
            if self.api_calls > self.budget.max_api_calls:
                self.abort(f"API call budget of {self.budget.max_api_calls} calls exceeded")
            return fn(*args, **kwargs)

        return counted

    def capped_range(self, *args: Any) -> range:
        r = range(*args)
        try:
            n = len(r)
        except OverflowError:
            n = sys.maxsize
        self.limit(n, "range()")
        return r

    def bounded(self, iterator: Iterable[Any], what: str) -> Iterator[Any]:
        """Yield from ``iterator`` but stop the run after ``max_elements`` elements."""
        produced = 0
        for i, item in enumerate(iterator):
            produced += len(item) if isinstance(item, tuple) else 1
            self.limit(produced, what)
            if not i & 1023:
                self.check_time()
            yield item


def _guarded(session: _Session, fn: Callable[..., Any], size: Callable[..., int],
             label: str) -> Callable[..., Any]:
    @_wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            n = size(*args, **kwargs)
        except (TypeError, ValueError, OverflowError, ZeroDivisionError):
            n = 0  # malformed arguments: the real function raises its own error
        session.limit(n, label)
        return fn(*args, **kwargs)

    return wrapper


def _int_capped(session: _Session, fn: Callable[..., Any], cap: int,
                label: str) -> Callable[..., Any]:
    """``fn`` refusing integer arguments above ``cap`` (its C loop could run for hours)."""
    @_wraps(fn)
    def wrapper(*args: Any) -> Any:
        if any(isinstance(a, int) and a > cap for a in args):
            session.abort(f"{label} arguments are limited to {cap}")
        return fn(*args)

    return wrapper


def _facades(session: _Session) -> dict[str, object]:
    """Fresh facades for one run (they close over the run's budget)."""
    import shapely.affinity
    import shapely.geometry

    np_members: dict[str, object] = {name: getattr(_np, name) for name in _NP_PLAIN}
    for name, size in _NP_ALLOCATORS.items():
        np_members[name] = _guarded(session, getattr(_np, name), size, f"np.{name}()")
    np_members["ndarray"] = _TypeCheck(_np.ndarray, "np.ndarray")
    np_members["linalg"] = _Facade("np.linalg", {n: getattr(_np.linalg, n)
                                                for n in ("norm", "inv", "det", "solve")})

    geometry = {n: getattr(shapely.geometry, n)
                for n in ("Point", "Polygon", "LineString", "MultiPoint", "MultiPolygon", "box")}
    affinity = {n: getattr(shapely.affinity, n) for n in ("rotate", "translate", "scale")}
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

        @_wraps(real)
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
        **geometry,
        **affinity,
    }


def _builtins(session: _Session, output: list[str] | None) -> dict[str, object]:
    """A fresh curated builtins dict: tampering in one run cannot reach the next."""
    table: dict[str, object] = {n: getattr(_builtins_module, n) for n in _SAFE_BUILTINS}
    printed = [0]

    def captured_print(*args: object, sep: str | None = " ", end: str | None = "\n",
                       file: object = None, flush: bool = False) -> None:
        text = (" " if sep is None else str(sep)).join(str(a) for a in args)
        if end not in (None, "\n"):
            text += str(end)
        if output is None or printed[0] > _MAX_PRINT_CHARS:
            return
        printed[0] += len(text)
        output.append(text if printed[0] <= _MAX_PRINT_CHARS else "[print output truncated]")

    table["print"] = captured_print
    table["range"] = session.capped_range
    return table


# ------------------------------------------------------------------------------------------------
# 5. entry points
# ------------------------------------------------------------------------------------------------
def _line_of(tb: types.TracebackType | None, filename: str) -> int | None:
    """Line of the innermost traceback entry that belongs to the sandboxed code."""
    line = None
    while tb is not None:
        if tb.tb_frame.f_code.co_filename == filename:
            line = tb.tb_lineno
        tb = tb.tb_next
    return line


def _execute(session: _Session, thunk: Callable[[], Any]) -> Any:
    """Run ``thunk`` under the session's tracer and deadline, translating every failure."""
    if session.active:  # re-entered from sandboxed code: already traced and budgeted
        return thunk()
    previous = sys.gettrace()
    session.active, session.lines, session.ticks, session.aborted = True, 0, 0, None
    session.deadline = time.monotonic() + session.budget.wall_s
    sys.settrace(session.global_trace)
    try:
        return thunk()
    except _Abort as exc:
        line = _line_of(exc.__traceback__, session.filename)
        raise BudgetExceeded(f"BudgetExceeded: {exc}", line=line, code=session.code) from None
    except Exception as exc:  # anything the code raised, including errors of env functions
        line = _line_of(exc.__traceback__, session.filename)
        kind = BudgetExceeded if isinstance(exc, BudgetExceeded) else PlanError
        detail = str(exc) if str(exc) else repr(exc)
        raise kind(f"{type(exc).__name__}: {detail}", line=line, code=session.code) from exc
    finally:
        sys.settrace(previous)
        session.active = False


def _sandboxed_function(session: _Session, fn: types.FunctionType) -> Callable[..., Any]:
    """A function defined by the code, callable later under the same budget and error rules."""
    @_wraps(fn)
    def call(*args: Any, **kwargs: Any) -> Any:
        return _execute(session, lambda: fn(*args, **kwargs))

    return call


def run_code(code: str, env: Mapping[str, object], *, budget: SandboxBudget = SandboxBudget(),
             filename: str = "<llm-code>", output: list[str] | None = None) -> dict[str, object]:
    """Check, rewrite and execute untrusted ``code`` with the names in ``env`` available.

    Callables in ``env`` (the robot/perception API) are wrapped to count towards
    ``budget.max_api_calls``; other values are passed as they are, so pass only objects whose
    public attributes are safe to expose.  ``print`` appends one string per call to ``output``
    (when given; never to stdout).  Returns the final namespace without builtins, facades,
    guards and unchanged ``env`` entries; functions the code defined are returned wrapped so
    that calling them later is budgeted and raises PlanError as well (wall time restarts per
    call, API calls accumulate).  ``wall_s`` is elapsed time, including time spent inside env
    functions (simulation, nested LLM calls); runs may nest (an env function may call
    ``run_code`` again) and each keeps its own budget.

    Raises PlanError (rejected or failing code) or BudgetExceeded, with the 1-based line.
    """
    tree = check_code(code)
    try:
        compiled = compile(ast.fix_missing_locations(_Rewriter().visit(tree)), filename, "exec")
    except SyntaxError as exc:  # e.g. 'return' outside function, found only by the compiler
        raise PlanError(f"SyntaxError: {exc.msg}", line=exc.lineno, code=code) from None
    except (RecursionError, MemoryError):
        raise PlanError("SandboxViolation: code is nested too deeply", code=code) from None
    session = _Session(budget, filename, code)
    namespace: dict[str, object] = {"__builtins__": _builtins(session, output),
                                    "__name__": "__llm_plan__"}
    namespace.update(_facades(session))
    for name, value in env.items():
        is_api = callable(value) and not isinstance(value, (type, _Facade, _TypeCheck))
        namespace[name] = session.count_calls(value) if is_api else value  # type: ignore[arg-type]
    namespace.update(session.helpers())
    injected = dict(namespace)
    _execute(session, lambda: exec(compiled, namespace))  # noqa: S102 - this is the sandbox
    result: dict[str, object] = {}
    for name, value in namespace.items():
        if name.startswith("__") or (name in injected and injected[name] is value):
            continue
        if isinstance(value, types.FunctionType) and value.__code__.co_filename == filename:
            value = _sandboxed_function(session, value)
        result[name] = value
    return result


_FENCE = re.compile(r"```[ \t]*([\w+.-]*)[^\n]*\n(.*?)(?:```|\Z)", re.DOTALL)
_CODE_LINE = re.compile(
    r"^\s*(#|def |for |while |if |elif |else\s*:|try\s*:|except\b|return\b|import |from \S+ import"
    r"|[A-Za-z_][\w.]*(\[[^\]]*\])?\s*(,\s*[A-Za-z_]\w*\s*)*[-+*/%]?=[^=]"  # assignment
    r"|[A-Za-z_][\w.]*\(.*\)\s*$)"  # call
)


def _looks_like_code(text: str) -> bool:
    try:
        tree = ast.parse(text)
    except (SyntaxError, ValueError):
        lines = [ln for ln in text.splitlines() if ln.strip()]
        return bool(lines) and 2 * sum(bool(_CODE_LINE.match(ln)) for ln in lines) >= len(lines)
    trivial = (ast.Constant, ast.Name)
    return any(not (isinstance(st, ast.Expr) and isinstance(st.value, trivial)) for st in tree.body)


def extract_code(completion_text: str) -> str:
    """The Python in an LLM answer: ```python blocks, else bare ``` blocks, else raw code.

    Several blocks of the chosen kind are joined in order; an unclosed fence (truncated answer)
    runs to the end.  Raises PlanError("no code in completion") for prose-only answers.
    """
    if not isinstance(completion_text, str) or not completion_text.strip():
        raise PlanError("no code in completion")
    blocks = [(lang.lower(), body) for lang, body in _FENCE.findall(completion_text)]
    if blocks:
        tagged = [b for lang, b in blocks if lang in ("python", "py", "python3")]
        chosen = tagged or [b for lang, b in blocks if not lang]
        code = "\n\n".join(textwrap.dedent(b).strip("\n") for b in chosen if b.strip())
        if code.strip():
            return code + "\n"
        raise PlanError("no code in completion")
    raw = textwrap.dedent(completion_text).strip("\n")
    if _looks_like_code(raw):
        return raw + "\n"
    raise PlanError("no code in completion")
