"""Layer 4 of the sandbox: the budgets of one run, the tracer that counts its lines, and the
guards the rewritten code calls.

A :class:`_Session` holds the mutable state of one run (executed lines, allocated elements,
API calls, wall-time deadline) and provides the ``__cap_*`` guards the rewritten code calls; a
``sys.settrace`` tracer restricted to sandbox frames counts lines, and violations raise
:class:`_Abort`, a ``BaseException`` that plan code's ``except Exception`` cannot swallow.

Budgets are deterministic first: executed lines (every ``while`` iteration counts too, so
``while True: pass`` stops after the same count on any machine), elements allocated through
checked constructors and operators (summed over the run), and API calls.  Wall time is only a
backstop, and the clock stops while an API function runs (simulation, nested LLM calls), so a
slow machine or a slow LLM never turns a passing program into a failing one.
"""

from __future__ import annotations

import inspect
import operator
import sys
import time
import types
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as _np

from capmj.agents.sandbox.facades import _checked_op, _growth, _wraps
from capmj.agents.sandbox.ordered import OrderedSet
from capmj.errors import ConfigError

MAX_INT_BITS = 1_000_000
"""Largest integer result (in bits) that ``**``, ``<<`` and ``*`` may produce."""

_SEQUENCES = (str, bytes, bytearray, list, tuple)


@dataclass(frozen=True)
class SandboxBudget:
    """Resources one run may use.

    ``max_lines``: executed lines plus ``while`` iterations (deterministic; None = unlimited).
    ``max_elements``: largest single allocation the guards can foresee; ``max_total_elements``:
    sum of those allocations over the run (None = unlimited).  ``wall_s``: backstop in seconds
    of the code's own time; time inside API (``env``) functions is not counted.
    """

    wall_s: float = 30.0
    max_api_calls: int = 500
    max_elements: int = 10_000_000
    max_lines: int | None = 100_000
    max_total_elements: int | None = 100_000_000

    def __post_init__(self) -> None:
        if not self.wall_s > 0 or self.max_api_calls < 0 or self.max_elements <= 0:
            raise ConfigError(f"invalid SandboxBudget {self}: wall_s and max_elements must be "
                              "positive, max_api_calls >= 0")
        for name in ("max_lines", "max_total_elements"):
            value = getattr(self, name)
            if value is not None and value <= 0:
                raise ConfigError(f"SandboxBudget.{name} must be positive or None, not {value}")


class _Abort(BaseException):
    """A budget violation; a BaseException so sandboxed ``except Exception`` cannot catch it."""


# ------------------------------------------------------------------------------------------------
# 4. one run: budgets, guards, tracer
# ------------------------------------------------------------------------------------------------
class _Session:
    """Mutable state of one ``run_code`` call (and of later calls of the functions it defined)."""

    def __init__(self, budget: SandboxBudget, filename: str, code: str,
                 program: str | None = None) -> None:
        self.budget, self.filename, self.code, self.program = budget, filename, code, program
        self.api_calls = 0
        self.lines = 0
        self.elements = 0
        self.deadline = float("inf")
        self.active = False
        self.aborted: str | None = None

    # -- budgets ---------------------------------------------------------------------------
    def abort(self, message: str) -> None:
        if not self.aborted:
            self.aborted = f"{message} (after {self.lines} executed lines, {self.api_calls} API calls)"
        raise _Abort(self.aborted)

    def check_time(self) -> None:
        if self.aborted:
            raise _Abort(self.aborted)
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

    def check_mul(self, a: Any, b: Any) -> Any:
        for seq, count in ((a, b), (b, a)):
            if isinstance(seq, _SEQUENCES) and not isinstance(count, (_SEQUENCES, _np.ndarray)):
                try:
                    self.allocate(len(seq) * operator.index(count), "sequence repetition")
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
            self.allocate(len(a) + len(b), "concatenation")
        return b

    def helpers(self) -> dict[str, object]:
        ops = {"mul": operator.mul, "pow": operator.pow, "lshift": operator.lshift,
               "add": operator.add}
        out: dict[str, object] = {
            "__cap_tick": self.tick, "__cap_rearm": self.rearm, "__cap_attr": self.attribute,
            "__cap_Exception": Exception, "__cap_set": OrderedSet,
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
                self.allocate(total + len(obj) * max(len(items) - 1, 0), f".{name}()")
                return value(items, *args[1:], **kwargs)
            try:
                n = _growth(obj, name, args, kwargs)
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

        @_wraps(fn)
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
