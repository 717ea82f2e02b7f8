"""Layer 4 of the sandbox and its entry point: budgets, the tracer and :func:`run_code`.

A :class:`_Session` holds the mutable state of one run (executed lines, allocated elements,
API calls, wall-time deadline) and provides the ``__cap_*`` guards the rewritten code calls; a
``sys.settrace`` tracer restricted to sandbox frames counts lines, and violations raise
:class:`_Abort`, a ``BaseException`` that plan code's ``except Exception`` cannot swallow.

Budgets are deterministic first: executed lines (every ``while`` iteration counts too, so
``while True: pass`` stops after the same count on any machine), elements allocated through
checked constructors and operators (summed over the run), and API calls.  Wall time is only a
backstop, and the clock stops while an API function runs (simulation, nested LLM calls), so a
slow machine or a slow LLM never turns a passing program into a failing one.

:func:`run_code` ties the layers together (check, rewrite, facades, budgeted ``exec``) and
translates every failure into a PlanError / BudgetExceeded that names the program (``program``,
e.g. "the plan") and quotes its failing line.
"""

from __future__ import annotations

import ast
import inspect
import operator
import sys
import time
import types
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as _np

from capmj.agents.sandbox.checks import _Rewriter, check_code
from capmj.agents.sandbox.facades import (_builtins, _checked_op, _Facade, _facades, _growth,
                                          _TypeCheck, _wraps)
from capmj.agents.sandbox.ordered import OrderedSet
from capmj.errors import BudgetExceeded, ConfigError, PlanError, PlanSyntaxError, SandboxViolation, error_name

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


WRITTEN_START = "# --- functions written by parse_function ---"
WRITTEN_END = "# --- end of written functions ---"
"""Markers around the functions ``parse_function`` wrote, prepended to the code that calls them."""


def _quote(code: str, line: int | None, limit: int = 160) -> str:
    lines = code.splitlines()
    if line is None or not 1 <= line <= len(lines):
        return ""
    text = lines[line - 1].strip()
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _region(code: str, line: int) -> str:
    """" (in the function f that parse_function wrote)" when ``line`` lies in that prefix."""
    lines = code.splitlines()
    if not lines or lines[0] != WRITTEN_START or WRITTEN_END not in lines:
        return ""
    if line > lines.index(WRITTEN_END):
        return ""
    for i in range(line - 1, -1, -1):
        if lines[i].startswith("def "):
            return f" (in {lines[i][4:].split('(')[0].strip()}(), written by parse_function)"
    return " (in the functions parse_function wrote)"


def _where(program: str, line: int | None, code: str) -> str:
    quoted = _quote(code, line)
    where = f"line {line} of {program}{_region(code, line)}" if line is not None else program
    return where + (f": `{quoted}`" if quoted else "")


def located_error(kind: type[PlanError], message: str, *, line: int | None, code: str,
                  program: str | None) -> PlanError:
    """A PlanError saying which program failed, at which line, quoting that line.

    Without ``program`` the classic ``"line N: message"`` form is kept.  The parts stay on the
    error (``program``, ``detail``) so that a caller whose API call ran this program (a helper
    LMP called from the plan) can say "in the code parse_obj_name wrote for this line, line 1".
    """
    if program is None:
        return kind(message, line=line, code=code)
    error = kind(f"{_where(program, line, code)}: {message}", code=code)
    error.line = line
    error.program, error.detail = program, message  # type: ignore[attr-defined]
    return error


def _describe(exc: BaseException) -> str:
    """"ErrorClass: message"; a located error of a nested program reads "in <program>, line N"."""
    program = getattr(exc, "program", None)
    if isinstance(exc, PlanError) and program is not None:
        code, line = exc.code or "", exc.line
        where = f"{program} for this line" + (f", line {line}{_region(code, line)}" if line else "")
        quoted = _quote(code, line)
        return f"in {where}" + (f": `{quoted}`" if quoted else "") + f": {exc.detail}"  # type: ignore[attr-defined]
    detail = str(exc) if str(exc) else repr(exc)
    return f"{error_name(exc)}: {detail}"


def _execute(session: _Session, thunk: Callable[[], Any]) -> Any:
    """Run ``thunk`` under the session's tracer and budgets, translating every failure."""
    if session.active:  # re-entered from sandboxed code: already traced and budgeted
        return thunk()
    previous = sys.gettrace()
    session.active, session.lines, session.elements, session.aborted = True, 0, 0, None
    session.deadline = time.monotonic() + session.budget.wall_s
    sys.settrace(session.global_trace)
    try:
        return thunk()
    except _Abort as exc:
        line = _line_of(exc.__traceback__, session.filename)
        raise located_error(BudgetExceeded, f"BudgetExceeded: {exc}", line=line, code=session.code,
                            program=session.program) from None
    except Exception as exc:  # anything the code raised, including errors of env functions
        line = _line_of(exc.__traceback__, session.filename)
        kind = BudgetExceeded if isinstance(exc, BudgetExceeded) else PlanError
        raise located_error(kind, _describe(exc), line=line, code=session.code,
                            program=session.program) from exc
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
             filename: str = "<llm-code>", output: list[str] | None = None,
             program: str | None = None,
             rng: _np.random.Generator | None = None) -> dict[str, object]:
    """Check, rewrite and execute untrusted ``code`` with the names in ``env`` available.

    Callables in ``env`` (the robot/perception API) are wrapped to count towards
    ``budget.max_api_calls``; other values are passed as they are, so pass only objects whose
    public attributes are safe to expose.  ``print`` appends one string per call to ``output``
    (when given; never to stdout).  Returns the final namespace without builtins, facades,
    guards and unchanged ``env`` entries; functions the code defined are returned wrapped so
    that calling them later is budgeted and raises PlanError as well (wall time restarts per
    call, API calls accumulate).  ``wall_s`` excludes time spent inside env functions
    (simulation, nested LLM calls); runs may nest (an env function may call ``run_code`` again)
    and each keeps its own budget.  ``np.random`` draws from ``rng`` (default: a generator
    seeded with 0), so the same code gives the same numbers in every process.

    Raises PlanError (rejected or failing code) or BudgetExceeded, with the 1-based line; with
    ``program`` (e.g. "the plan") the message names it and quotes the line.
    """
    try:
        tree = check_code(code)
    except PlanError as exc:
        if program is None:
            raise
        message = str(exc)[len(f"line {exc.line}: "):] if exc.line is not None else str(exc)
        raise located_error(type(exc), message, line=exc.line, code=code, program=program) from None
    try:
        compiled = compile(ast.fix_missing_locations(_Rewriter().visit(tree)), filename, "exec")
    except SyntaxError as exc:  # e.g. 'return' outside function, found only by the compiler
        raise located_error(PlanSyntaxError, f"SyntaxError: {exc.msg}", line=exc.lineno, code=code,
                            program=program) from None
    except (RecursionError, MemoryError):
        raise SandboxViolation("SandboxViolation: code is nested too deeply", code=code) from None
    session = _Session(budget, filename, code, program)
    namespace: dict[str, object] = {"__builtins__": _builtins(session, output),
                                    "__name__": "__llm_plan__"}
    namespace.update(_facades(session, rng if rng is not None else _np.random.default_rng(0)))
    for name, value in env.items():
        is_api = callable(value) and not isinstance(value, (type, _Facade, _TypeCheck))
        namespace[name] = session.count_calls(value, name) if is_api else value  # type: ignore[arg-type]
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
