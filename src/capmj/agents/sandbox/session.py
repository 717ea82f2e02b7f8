"""Layer 4 of the sandbox: the budgets of one run, the tracer that counts its lines, and the
guards the rewritten code calls.

A :class:`Session` holds the mutable state of one run (executed lines, allocated elements,
API calls, wall-time deadline) and provides the ``__cap_*`` guards the rewritten code calls; a
``sys.settrace`` tracer restricted to sandbox frames counts lines, and violations raise
:class:`Abort`, a ``BaseException`` that plan code's ``except Exception`` cannot swallow.

Budgets are deterministic first: executed lines (every ``while`` iteration counts too, so
``while True: pass`` stops after the same count on any machine), elements allocated through
checked constructors and operators (summed over the run; a nested list turned into an array and
the broadcast result of an operation on arrays are counted before numpy makes them, see
:mod:`~capmj.agents.sandbox.sizes`), characters of text made from plan values (``print``,
``str``/``repr``, f-strings, ``format``, ``%``; counted before the text is made), and API calls.
Wall time is only a backstop, and the clock stops while an API function runs (simulation, nested
LLM calls), so a slow machine or a slow LLM never turns a passing program into a failing one.

A budget an API function reports (a :class:`~capmj.errors.BudgetExceeded` it raises itself, or an
episode's LLM budget from wherever it comes) ends the run as the sandbox's own budgets do: plan
code cannot catch it and carry on.  A budget of a nested program (a helper LMP's code) is that
program's failure, which the caller may catch.
"""

from __future__ import annotations

import inspect
import operator
import sys
import time
import types
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from operator import eq, ge, gt, is_, is_not, le, lt, ne  # by name: the layer check reads .eq as MjModel's
from typing import Any

import numpy as _np

from capmj.agents.sandbox.checks import FORMAT_FIELD_RULE, THUNK_ARG, format_fields, reaching_field
from capmj.agents.sandbox.facades import checked_op, growth, wraps
from capmj.agents.sandbox.located import describe
from capmj.agents.sandbox.ordered import OrderedSet
from capmj.agents.sandbox.sizes import array_elements, broadcast_elements, matmul_elements, text_length
from capmj.errors import BudgetExceeded, ConfigError, LLMBudgetExceeded, PlanError, SandboxViolation, TextBudgetExceeded

MAX_INT_BITS = 1_000_000
"""Largest integer result (in bits) that ``**``, ``<<`` and ``*`` may produce."""

_SEQUENCES = (str, bytes, bytearray, list, tuple)

_COMPARISONS: Mapping[str, Callable[[Any, Any], Any]] = {
    "lt": lt, "le": le, "gt": gt, "ge": ge, "eq": eq, "ne": ne, "in": lambda a, b: a in b,
    "not_in": lambda a, b: a not in b, "is": is_, "is_not": is_not,
}
"""The comparisons the rewritten code routes through :meth:`Session.compare`, by guard name."""

_ARITHMETIC: Mapping[str, tuple[Callable[[Any, Any], Any], str]] = {
    "add": (operator.add, "+"), "sub": (operator.sub, "-"), "mul": (operator.mul, "*"),
    "truediv": (operator.truediv, "/"), "floordiv": (operator.floordiv, "//"), "mod": (operator.mod, "%"),
    "pow": (operator.pow, "**"), "lshift": (operator.lshift, "<<"), "rshift": (operator.rshift, ">>"),
    "and": (operator.and_, "&"), "or": (operator.or_, "|"), "xor": (operator.xor, "^"),
    "matmul": (operator.matmul, "@"),
}
"""The binary operators the rewritten code routes through ``__cap_<name>`` guards."""


def _root(error: BaseException) -> BaseException:
    """The end of a located error's ``__cause__`` chain (what really happened)."""
    seen = {id(error)}
    while isinstance(error, PlanError) and error.__cause__ is not None and id(error.__cause__) not in seen:
        error = error.__cause__
        seen.add(id(error))
    return error


@dataclass(frozen=True)
class SandboxBudget:
    """Resources one run may use.

    ``max_lines``: executed lines plus ``while`` iterations (deterministic; None = unlimited).
    ``max_elements``: largest single allocation the guards can foresee; ``max_total_elements``:
    sum of those allocations over the run (None = unlimited).  ``max_text_chars``: characters
    of one text made from a value (``str``, ``repr``, an f-string field, ``format``, ``%``) and of
    all ``print`` output of the run together.  ``wall_s``: backstop in seconds of the code's own
    time; time inside API (``env``) functions is not counted.
    """

    wall_s: float = 30.0
    max_api_calls: int = 500
    max_elements: int = 10_000_000
    max_lines: int | None = 100_000
    max_total_elements: int | None = 100_000_000
    max_text_chars: int = 1_000_000

    def __post_init__(self) -> None:
        if not self.wall_s > 0 or self.max_api_calls < 0 or self.max_elements <= 0 or self.max_text_chars <= 0:
            raise ConfigError(f"invalid SandboxBudget {self}: wall_s, max_elements and max_text_chars must be "
                              "positive, max_api_calls >= 0")
        for name in ("max_lines", "max_total_elements"):
            value = getattr(self, name)
            if value is not None and value <= 0:
                raise ConfigError(f"SandboxBudget.{name} must be positive or None, not {value}")


class Abort(BaseException):
    """The end of a run: a budget violation or a refused operation; a BaseException so sandboxed
    ``except Exception`` cannot catch it.  ``error`` is what the run fails with (its class is
    the one recorded), ``text`` how the failure reads ("ErrorClass: message")."""

    def __init__(self, text: str, error: PlanError) -> None:
        super().__init__(text)
        self.text, self.error = text, error




# ------------------------------------------------------------------------------------------------
# 4. one run: budgets, guards, tracer
# ------------------------------------------------------------------------------------------------
class Session:
    """Mutable state of one ``run_code`` call (and of later calls of the functions it defined)."""

    def __init__(self, budget: SandboxBudget, filename: str, code: str,
                 program: str | None = None) -> None:
        self.budget, self.filename, self.code, self.program = budget, filename, code, program
        self.api_calls = 0
        self.lines = 0
        self.elements = 0
        self.deadline = float("inf")
        self.active = False
        self.aborted: tuple[str, PlanError] | None = None
        """Once the run ended: its failure's text and error (raised again at every later check)."""

    # -- budgets ---------------------------------------------------------------------------
    def abort(self, message: str, kind: type[BudgetExceeded] = BudgetExceeded) -> None:
        """End the run with a budget failure of class ``kind``: ``message`` names the limit."""
        if not self.aborted:
            detail = f"{message} (after {self.lines} executed lines, {self.api_calls} API calls)"
            self.aborted = (f"{kind.__name__}: {detail}", kind(detail))
        raise Abort(*self.aborted)

    def refuse(self, message: str) -> None:
        """End the run as refused code (:class:`SandboxViolation`), as the static check would."""
        if not self.aborted:
            self.aborted = (f"SandboxViolation: {message}", SandboxViolation(message))
        raise Abort(*self.aborted)

    def end_with(self, error: BaseException) -> None:
        """End the run with ``error``, a budget an API function reported (see the module docstring)."""
        if not self.aborted:
            self.aborted = (describe(error), error if isinstance(error, PlanError) else BudgetExceeded(str(error)))
        raise Abort(*self.aborted)

    def check_time(self) -> None:
        if self.aborted:
            raise Abort(*self.aborted)
        if time.monotonic() > self.deadline:
            self.abort(f"wall time budget of {self.budget.wall_s:g} s exceeded (a backstop; "
                       "time inside API functions is not counted)")

    def limit(self, n: int, what: str) -> None:
        if n > self.budget.max_elements:
            self.abort(f"{what} would create {n} elements (max_elements="
                       f"{self.budget.max_elements})")

    def allocate(self, n: int, what: str) -> None:
        """``limit`` one allocation and add it to the run's total."""
        self.limit(n, what)
        self.elements += max(int(n), 0)
        cap = self.budget.max_total_elements
        if cap is not None and self.elements > cap:
            self.abort(f"allocation budget of {cap} elements per run exceeded by {what}")

    def step(self) -> None:
        """One executed line or loop iteration."""
        self.lines += 1
        if self.budget.max_lines is not None and self.lines > self.budget.max_lines:
            self.abort(f"executed-line budget of {self.budget.max_lines} lines exceeded")
        if not self.lines & 63:
            self.check_time()

    def global_trace(self, frame: types.FrameType, event: str, arg: object) -> Any:
        if frame.f_code.co_filename != self.filename:
            return None  # library frames run untraced (fast); their callers are traced
        self.check_time()
        if frame.f_code.co_varnames[:1] == (THUNK_ARG,):
            return None  # an operand the rewrite wrapped (see checks.Rewriter): not a line of the code
        return self.local_trace

    def local_trace(self, frame: types.FrameType, event: str, arg: object) -> Any:
        if event == "line":
            self.step()
        return self.local_trace

    # -- helpers the rewritten code calls ---------------------------------------------------
    def tick(self) -> None:
        self.step()

    def rearm(self) -> None:
        self.check_time()
        if sys.gettrace() is None:
            sys.settrace(self.global_trace)
            frame: types.FrameType | None = sys._getframe(1)
            while frame is not None:
                if frame.f_code.co_filename == self.filename:
                    frame.f_trace = self.local_trace
                frame = frame.f_back

    # .. arrays: conversions of nested sequences and broadcast results, before numpy makes them
    def check_array(self, a: Any, b: Any, what: str, size: Callable[[Any, Any], int] = broadcast_elements) -> None:
        """Count the array an operation of ``a`` and ``b`` makes (``size``: broadcasting by default)
        and every nested list or tuple it turns into an array, when one operand is a numpy value."""
        if not (isinstance(a, _np.ndarray) or isinstance(b, _np.ndarray)
                or (isinstance(a, _np.generic) or isinstance(b, _np.generic))
                and (isinstance(a, (list, tuple)) or isinstance(b, (list, tuple)))):
            return
        self.check_inputs((a, b), what)
        self.allocate(size(a, b), what)

    def check_inputs(self, values: Iterable[Any], what: str) -> None:
        """Count the arrays numpy makes of the nested lists and tuples among ``values``."""
        for value in values:
            if isinstance(value, (list, tuple)):
                cap = max(self.budget.max_elements, self.budget.max_total_elements or 0)
                self.allocate(array_elements(value, cap), f"a nested sequence turned into an array by {what}")

    def check_mul(self, a: Any, b: Any) -> Any:
        for seq, count in ((a, b), (b, a)):
            if isinstance(seq, _SEQUENCES) and not isinstance(count, (_SEQUENCES, _np.ndarray)):
                try:
                    self.allocate(len(seq) * operator.index(count), "sequence repetition")
                except TypeError:
                    pass
                break  # a numpy scalar count may still turn the sequence into an array: checked below
        if isinstance(a, int) and isinstance(b, int) and (
                a.bit_length() + b.bit_length() > MAX_INT_BITS):
            self.abort(f"integer product would exceed {MAX_INT_BITS} bits")
        self.check_array(a, b, "'*'")
        return b

    def check_pow(self, a: Any, b: Any) -> Any:
        if isinstance(a, int) and isinstance(b, int) and b > 0 and abs(a) > 1:
            if b * abs(a).bit_length() > MAX_INT_BITS:
                self.abort(f"integer power would exceed {MAX_INT_BITS} bits")
        self.check_array(a, b, "'**'")
        return b

    def check_lshift(self, a: Any, b: Any) -> Any:
        if isinstance(a, int) and isinstance(b, int) and a and a.bit_length() + b > MAX_INT_BITS:
            self.abort(f"integer shift would exceed {MAX_INT_BITS} bits")
        self.check_array(a, b, "'<<'")
        return b

    def check_add(self, a: Any, b: Any) -> Any:
        if isinstance(a, _SEQUENCES) and isinstance(b, _SEQUENCES):
            self.allocate(len(a) + len(b), "concatenation")
        self.check_array(a, b, "'+'")
        return b

    def check_mod(self, a: Any, b: Any) -> Any:
        if isinstance(a, (str, bytes)):  # printf-style formatting: the arguments' text
            self.check_text(b, "'%' formatting", as_repr=True, extra=len(a))
        self.check_array(a, b, "'%'")
        return b

    def check_matmul(self, a: Any, b: Any) -> Any:
        self.check_array(a, b, "'@'", matmul_elements)
        return b

    def _elementwise(self, symbol: str) -> Callable[[Any, Any], Any]:
        def check(a: Any, b: Any) -> Any:
            self.check_array(a, b, f"'{symbol}'")
            return b

        return check

    def compare(self, name: str) -> Callable[[Any, Any], Any]:
        """The guarded comparison ``__cap_cmp_<name>`` (``a < b`` of arrays broadcasts like ``+``)."""
        op = _COMPARISONS[name]
        what = f"a comparison ({name.replace('_', ' ')})"
        if name in ("is", "is_not"):
            return op
        if name in ("in", "not_in"):  # ``x in arr`` compares x with every element of arr
            def contains(a: Any, b: Any) -> Any:
                if isinstance(b, _np.ndarray):
                    self.check_inputs((a,), what)
                    self.allocate(broadcast_elements(a, b), what)
                return op(a, b)

            return contains

        def compare(a: Any, b: Any) -> Any:
            self.check_array(a, b, what)
            return op(a, b)

        return compare

    def chain(self, names: tuple[str, ...], *operands: Callable[[], Any]) -> Any:
        """``a < b <= c``: each operand evaluated once and in order, each pair checked before it
        is compared, stopping at the first false result (Python's chained comparison)."""
        left = operands[0]()
        result: Any = True
        for name, operand in zip(names, operands[1:]):
            right = operand()
            result = self.compare(name)(left, right)
            if not result:
                return result
            left = right
        return result

    # .. text made from values, counted before it is made
    def check_text(self, value: Any, what: str, *, as_repr: bool = False, extra: int = 0) -> None:
        """Refuse (uncatchably) a text of ``value`` longer than ``max_text_chars`` minus ``extra``."""
        cap = self.budget.max_text_chars
        if text_length(value, max(cap - extra, 0), as_repr=as_repr) is None:
            self.abort(f"{what} would make more than {cap} characters of text (max_text_chars)", TextBudgetExceeded)

    def field(self, value: Any, conversion: int = -1) -> Any:
        """An f-string field's value, after checking the size of its text."""
        self.check_text(value, "an f-string field", as_repr=conversion in (ord("r"), ord("a")))
        return value

    def text_call(self, fn: Any, *args: Any, **kwargs: Any) -> Any:
        """``fn(*args, **kwargs)`` for a call written ``str(x)`` or ``repr(x)``: when ``fn`` is the
        builtin, the size of the text is checked first."""
        if fn is str and len(args) + len(kwargs) == 1 and (args or "object" in kwargs):
            self.check_text(args[0] if args else kwargs["object"], "str()")
        elif fn is repr and len(args) == 1 and not kwargs:
            self.check_text(args[0], "repr()", as_repr=True)
        return fn(*args, **kwargs)

    def checked_repr(self, value: Any) -> str:
        """The builtin ``repr`` of plan code (also when passed around: ``map(repr, xs)``)."""
        self.check_text(value, "repr()", as_repr=True)
        return repr(value)

    def checked_format(self, template: Any, method: Callable[..., Any], name: str) -> Callable[..., Any]:
        """``template.format`` / ``.format_map`` (or ``str.format`` itself, ``template`` None):
        fields that reach attributes or items are refused as dunders are, and the text of the
        arguments the fields use is counted before the result is made."""
        @wraps(method)
        def call(*args: Any, **kwargs: Any) -> Any:
            text, rest = (template, args) if template is not None else (args[0] if args else None, args[1:])
            if isinstance(text, str):
                field = reaching_field(text)
                if field is not None:
                    self.refuse(f"format field {{{field}}} reaches an attribute or an item of an argument; "
                                f"{FORMAT_FIELD_RULE}")
                used = _used_arguments(text, rest, kwargs, name)
                self.check_text(used, f"str.{name}()", as_repr=True, extra=len(text))
            return method(*args, **kwargs)

        return call

    def helpers(self) -> dict[str, object]:
        out: dict[str, object] = {
            "__cap_tick": self.tick, "__cap_rearm": self.rearm, "__cap_attr": self.attribute,
            "__cap_Exception": Exception, "__cap_set": OrderedSet, "__cap_field": self.field,
            "__cap_text_call": self.text_call, "__cap_chain": self.chain,
        }
        for name, (op, symbol) in _ARITHMETIC.items():
            check = getattr(self, f"check_{name}", None) or self._elementwise(symbol)
            out[f"__cap_{name}_check"] = check  # for ``x op= y``: returns y after checking
            out[f"__cap_{name}"] = checked_op(check, op)
        for name in _COMPARISONS:
            out[f"__cap_cmp_{name}"] = self.compare(name)
        return out

    def attribute(self, obj: Any, name: str) -> Any:
        """``obj.name`` for a growing method, size-checked when ``obj`` is an array or string;
        ``format``/``format_map`` of a string (or of ``str``) through :meth:`checked_format`."""
        value = getattr(obj, name)
        if name in ("format", "format_map") and (isinstance(obj, str) or obj is str) and callable(value):
            return self.checked_format(obj if isinstance(obj, str) else None, value, name)
        if not isinstance(obj, (_np.ndarray, str, bytes, bytearray)) or not callable(value):
            return value

        @wraps(value)
        def checked(*args: Any, **kwargs: Any) -> Any:
            if name == "join" and args:
                items, total = [], 0
                for item in args[0]:  # counted as they come: a generator of big texts stops early
                    items.append(item)
                    total += (len(item) if isinstance(item, _SEQUENCES) else 0) + (len(obj) if len(items) > 1 else 0)
                    self.limit(total, f".{name}()")
                self.allocate(total, f".{name}()")
                return value(items, *args[1:], **kwargs)
            try:
                n = growth(obj, name, args, kwargs)
            except (TypeError, ValueError, IndexError, KeyError):
                n = 0  # malformed call: let the real method raise its own error
            self.allocate(n, f".{name}()")
            return value(*args, **kwargs)

        return checked

    def count_calls(self, fn: Callable[..., Any], name: str) -> Callable[..., Any]:
        """``fn`` counted against the API-call budget, its own time off the wall clock, and a
        wrong call answered with the function's signature."""
        try:
            signature: inspect.Signature | None = inspect.signature(fn)
        except (TypeError, ValueError):
            signature = None

        @wraps(fn)
        def counted(*args: Any, **kwargs: Any) -> Any:
            self.check_time()
            self.api_calls += 1
            if self.api_calls > self.budget.max_api_calls:
                self.abort(f"API call budget of {self.budget.max_api_calls} calls exceeded")
            if signature is not None:
                try:
                    signature.bind(*args, **kwargs)
                except TypeError as exc:
                    raise TypeError(f"{exc}; call it as {name}{_plain(signature)}") from None
            start = time.monotonic()
            try:
                return fn(*args, **kwargs)
            except BudgetExceeded as exc:  # the API's own budget, or the episode's LLM budget: the run ends
                if getattr(exc, "program", None) is None or isinstance(_root(exc), LLMBudgetExceeded):
                    self.end_with(exc)
                raise
            finally:  # simulation and LLM waits are not the code's time
                self.deadline += time.monotonic() - start

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


def _plain(signature: inspect.Signature) -> str:
    """``(obj, target)``: a signature without annotations, as the prompts write calls."""
    params = [p.replace(annotation=inspect.Parameter.empty) for p in signature.parameters.values()]
    return str(signature.replace(parameters=params, return_annotation=inspect.Signature.empty))


def _used_arguments(template: str, args: tuple[Any, ...], kwargs: Mapping[str, Any], name: str) -> list[Any]:
    """The arguments the fields of a ``str.format`` template use (``format_map``: its mapping's)."""
    mapping: Any = (args[0] if args else {}) if name == "format_map" else kwargs
    used: list[Any] = []
    auto = 0
    try:
        fields = list(format_fields(template))
    except ValueError:
        return used
    for field in fields:
        key: Any = field
        if field == "":
            key, auto = auto, auto + 1
        elif field.isdigit():
            key = int(field)
        try:
            used.append(args[key] if isinstance(key, int) and name == "format" else mapping[key])
        except (IndexError, KeyError, TypeError):
            pass  # the real call raises its own error
    return used
