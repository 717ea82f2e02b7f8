"""Static checks of generated task code: parse, import allow-list, forbidden names.

They read the code as an AST and never execute it, so ``import os`` or ``open(...)`` is
rejected before anything runs.  The allow-list is what a task may use (issue #9): ``numpy``,
``math``, ``itertools``, ``capmj.tasks.*``, ``capmj.sim.state``, ``capmj.sim.objects``, plus the
declaration-only ``__future__``, ``typing`` and ``dataclasses``.  Execution (and with it the
registry's validation of the task object) happens only in the limited worker process.
"""

from __future__ import annotations

import ast
import json
import re
from typing import Any

from capmj.agents.sandbox.checks import FORBIDDEN_ATTRIBUTES
from capmj.taskcheck import CheckResult

ALLOWED_IMPORTS: tuple[str, ...] = (
    "numpy", "math", "itertools", "capmj.tasks", "capmj.sim.state", "capmj.sim.objects",
    "__future__", "typing", "dataclasses",
)
"""A module is allowed when it equals one of these or lies below it (``capmj.tasks.spawn``)."""

FORBIDDEN_CALLS = frozenset({
    "open", "exec", "eval", "compile", "__import__", "globals", "locals", "vars", "input", "breakpoint",
    "getattr", "setattr", "delattr", "exit", "quit", "memoryview", "help",
})
"""Names a task has no business calling: I/O, dynamic code, reflection that escapes the AST check."""
_DUNDER_OK = frozenset({"__init__", "__post_init__", "__repr__", "__name__", "__doc__", "__future__"})

STATIC_CHECKS = ("parse", "imports", "names")


def extract_code(answer: str) -> str:
    """The code of an LLM answer: the longest fenced block (```python or bare), else the text."""
    blocks = re.findall(r"```[a-zA-Z0-9_+-]*[ \t]*\n(.*?)```", answer, re.DOTALL)
    return (max(blocks, key=len) if blocks else answer).strip() + "\n"


def extract_json(answer: str) -> Any:
    """The first JSON value of an LLM answer (fenced or bare); raises ``ValueError``."""
    text = answer.strip()
    fenced = re.search(r"```(?:json)?\s*\n(.*?)```", text, re.DOTALL)
    if fenced:
        text = fenced.group(1).strip()
    starts = [i for i in (text.find("{"), text.find("[")) if i >= 0]
    if not starts:
        raise ValueError(f"no JSON value in the answer: {answer[:200]!r}")
    value, _ = json.JSONDecoder().raw_decode(text[min(starts):])
    return value


def import_allowed(module: str) -> bool:
    return any(module == a or module.startswith(a + ".") for a in ALLOWED_IMPORTS)


def _imports(tree: ast.AST) -> list[str]:
    bad = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            bad += [f"line {node.lineno}: import of {a.name!r}" for a in node.names if not import_allowed(a.name)]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                bad.append(f"line {node.lineno}: relative import")
            elif not import_allowed(node.module or ""):
                bad.append(f"line {node.lineno}: import from {node.module!r}")
    return bad


def _names(tree: ast.AST) -> list[str]:
    bad = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and node.id in FORBIDDEN_CALLS | {"__builtins__"}:
            bad.append(f"line {node.lineno}: {node.id!r} is not allowed in a task")
        elif isinstance(node, ast.Attribute):
            a = node.attr
            if (a.startswith("__") and a not in _DUNDER_OK) or a in FORBIDDEN_ATTRIBUTES:
                bad.append(f"line {node.lineno}: attribute {a!r} is not allowed in a task")
            elif (a != "Generator" and isinstance(node.value, ast.Attribute) and node.value.attr == "random"
                  and isinstance(node.value.value, ast.Name) and node.value.value.id in ("np", "numpy")):
                bad.append(f"line {node.lineno}: np.random.{a} is global or unseeded state; draw from the rng argument")
        elif isinstance(node, ast.ImportFrom) and node.module == "numpy.random":
            if any(n.name != "Generator" for n in node.names):
                bad.append(f"line {node.lineno}: numpy.random functions are global state; draw from the rng argument")
    return bad


def static_checks(code: str) -> tuple[CheckResult, ...]:
    """``parse``, ``imports`` and ``names`` in order; after a failure the rest are skipped."""
    try:
        tree = ast.parse(code)
        compile(tree, "<task>", "exec")
    except SyntaxError as e:
        msg = f"SyntaxError: {e.msg} (line {e.lineno})" + (f": {e.text.strip()}" if e.text else "")
        return (CheckResult("parse", "fail", msg), CheckResult("imports", "skip"), CheckResult("names", "skip"))
    out = [CheckResult("parse", "pass", f"{len(code.splitlines())} lines")]
    bad = _imports(tree)
    allowed = ", ".join(ALLOWED_IMPORTS)
    out.append(CheckResult("imports", "fail", f"{'; '.join(bad)}; a task may import only {allowed}") if bad
               else CheckResult("imports", "pass", "only allowed modules"))
    if bad:
        return (*out, CheckResult("names", "skip"))
    bad = _names(tree)
    out.append(CheckResult("names", "fail", "; ".join(bad[:5])) if bad else CheckResult("names", "pass", "no forbidden names"))
    return tuple(out)


__all__ = ["ALLOWED_IMPORTS", "FORBIDDEN_CALLS", "STATIC_CHECKS", "extract_code", "extract_json", "import_allowed",
           "static_checks"]
