"""The sandbox's entry point: :func:`run_code` ties the layers together (check, rewrite, facades,
budgeted ``exec``) and translates every failure into a PlanError / BudgetExceeded that names the
program (``program``, e.g. "the plan") and quotes its failing line.

The layers: :mod:`~capmj.agents.sandbox.checks` (the static allow-list and the rewrite),
:mod:`~capmj.agents.sandbox.facades` (modules and builtins as vetted namespaces),
:mod:`~capmj.agents.sandbox.session` (budgets, guards, tracer); how a failure is located and
worded, :mod:`~capmj.agents.sandbox.located`.
"""

from __future__ import annotations

import ast
import sys
import time
import types
from collections.abc import Callable, Mapping
from typing import Any

import numpy as _np

from capmj.agents.sandbox.checks import Rewriter, check_code
from capmj.agents.sandbox.facades import is_api_function, run_namespace, wraps
from capmj.agents.sandbox.located import describe, line_of, located_error
from capmj.agents.sandbox.session import Abort, SandboxBudget, Session
from capmj.errors import BudgetExceeded, PlanError, PlanSyntaxError, SandboxViolation

DEFAULT_BUDGET = SandboxBudget()
"""The budget of a run that names none (frozen, so one instance serves every call)."""

def _execute(session: Session, thunk: Callable[[], Any]) -> Any:
    """Run ``thunk`` under the session's tracer and budgets, translating every failure."""
    if session.active:  # re-entered from sandboxed code: already traced and budgeted
        return thunk()
    previous = sys.gettrace()
    session.active, session.lines, session.elements, session.aborted = True, 0, 0, None
    session.deadline = time.monotonic() + session.budget.wall_s
    sys.settrace(session.global_trace)
    try:
        return thunk()
    except Abort as exc:  # a budget or a refusal: the class recorded is that of exc.error
        line = line_of(exc.__traceback__, session.filename)
        raise located_error(type(exc.error), exc.text, line=line, code=session.code,
                            program=session.program) from exc.error
    except MemoryError as exc:  # the worker's memory limit: the backstop for what the counting cannot see
        line = line_of(exc.__traceback__, session.filename)
        raise located_error(BudgetExceeded, "BudgetExceeded: the process ran out of memory (its memory limit "
                            "is the backstop of the sandbox's size budgets)", line=line, code=session.code,
                            program=session.program) from None
    except Exception as exc:  # anything the code raised, including errors of env functions
        line = line_of(exc.__traceback__, session.filename)
        kind = BudgetExceeded if isinstance(exc, BudgetExceeded) else PlanError
        raise located_error(kind, describe(exc), line=line, code=session.code,
                            program=session.program) from exc
    finally:
        sys.settrace(previous)
        session.active = False


def _sandboxed_function(session: Session, fn: types.FunctionType) -> Callable[..., Any]:
    """A function defined by the code, callable later under the same budget and error rules."""
    @wraps(fn)
    def call(*args: Any, **kwargs: Any) -> Any:
        return _execute(session, lambda: fn(*args, **kwargs))

    return call


def run_code(code: str, env: Mapping[str, object], *, budget: SandboxBudget = DEFAULT_BUDGET,
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
        compiled = compile(ast.fix_missing_locations(Rewriter().visit(tree)), filename, "exec")
    except SyntaxError as exc:  # e.g. 'return' outside function, found only by the compiler
        raise located_error(PlanSyntaxError, f"SyntaxError: {exc.msg}", line=exc.lineno, code=code,
                            program=program) from None
    except (RecursionError, MemoryError):
        raise SandboxViolation("SandboxViolation: code is nested too deeply", code=code) from None
    session = Session(budget, filename, code, program)
    namespace = run_namespace(session, output, rng if rng is not None else _np.random.default_rng(0))
    for name, value in env.items():
        namespace[name] = session.count_calls(value, name) if is_api_function(value) else value  # type: ignore[arg-type]
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