"""Static preparation of LLM-written code before it reaches the sandbox.

Completions are not run as written: import lines that merely echo the prompt header are
dropped (also star imports of provided modules, ``from shapely.geometry import *``), and calls
of functions nobody defined are found so that ``parse_function`` can write them (see
:class:`capmj.agents.lmp.session.LMPSession`) -- except names that belong to the API, the LMPs, the
sandbox or the episode (:data:`RESERVED`), which are never invented: calling one where it is not
available is a PlanError saying why and what exists.  All of that is pure AST work on source text,
with no LLM or environment involved, so it lives here and can be tested on its own.  Everything
is line-preserving where it matters: the sandbox reports errors by line of the submitted code.
"""

from __future__ import annotations

import ast
import builtins
import re
from collections.abc import Iterator

from capmj.agents.sandbox import FORBIDDEN_NAMES, PROVIDED_NAMES
from capmj.agents.sandbox.checks import bound_names
from capmj.errors import FunctionNotWritten, PlanSyntaxError

__all__ = [
    "RESERVED",
    "SANDBOX_GLOBALS",
    "bound_names",
    "function_defs",
    "named_calls",
    "strip_benign_imports",
    "undefined_calls",
]

SANDBOX_GLOBALS = PROVIDED_NAMES
"""What run_code provides besides env (facades, shapely shortcuts, curated builtins)."""

# Modules the prompts "import" in their header: LLMs often repeat such lines; they are dropped
# when every name they bind is already available.  Any other import reaches the sandbox, which
# rejects it (and ends the attempt with a recorded error).
_BENIGN_MODULES = frozenset({"numpy", "math", "itertools", "shapely", "shapely.geometry",
                             "shapely.affinity", "env_utils", "plan_utils", "utils",
                             "cliport.utils"})
# ``from M import *`` is dropped for these: every public name code uses from them is provided
# (shapely's geometry classes and affinity functions are globals; the API modules are the env).
_STAR_MODULES = frozenset({"shapely.geometry", "shapely.affinity", "env_utils", "plan_utils", "utils"})

RESERVED: dict[str, str] = {
    "put_first_on_second": "it moves the robot, and only the plan may move the robot",
    "stack_objects_in_order": "it moves the robot, and only the plan may move the robot",
    "parse_obj_name": "it is a helper LMP that the plan and helper code up to LMPSession.max_helper_depth "
                      "levels deep may call: parse_obj_name(description, context=None) returns object names",
    "parse_position": "it is a helper LMP that the plan and helper code up to LMPSession.max_helper_depth "
                      "levels deep may call: parse_position(description, context=None) returns a position or pose",
    "parse_question": "it is a helper LMP that the plan and helper code up to LMPSession.max_helper_depth "
                      "levels deep may call: parse_question(question, context=None) returns the answer",
    "parse_function": "it writes missing functions before code runs; code does not call it",
    "parse_completion": "it is the text reporter's check: only the plan of an agent with an LLM may call it, "
                        "parse_completion(goal, context=None) returns whether the goal is achieved now",
    "tabletop_ui": "it is the planner itself; write the plan's statements directly",
    "reset": "it restores the episode's initial scene, which only the plan may do",
    "run_code": "code cannot run code",
    "exec_safe": "code cannot run code",
}
"""Names never synthesised by ``parse_function``, with the reason shown when code calls one
where it is not available (API functions absent from a helper's env are added by the session)."""


def named_calls(tree: ast.AST, name: str | None = None) -> Iterator[tuple[str, ast.Call]]:
    """The calls of a bare name in ``tree`` (only those of ``name`` when given), as ``(name, call)``."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and name in (None, node.func.id):
            yield node.func.id, node


def undefined_calls(code: str, known: set[str] | frozenset[str]) -> list[tuple[str, int, str]]:
    """Functions ``code`` calls by a bare name that neither ``known`` nor the code itself binds.

    Returns ``(name, line, statement source)`` for the first call site of each, in order of
    appearance.  Unparseable code gives ``[]`` (the sandbox reports the syntax error).  Names the
    sandbox forbids (``eval``, ``open``...) are never offered for synthesis.
    """
    try:
        tree = ast.parse(code)
    except (SyntaxError, ValueError):
        return []
    bound = bound_names(tree) | set(known) | SANDBOX_GLOBALS
    lines = code.splitlines()
    statements = [n for n in ast.walk(tree) if isinstance(n, ast.stmt)]
    found: dict[str, tuple[str, int, str]] = {}
    for name, call in sorted(named_calls(tree), key=lambda nc: (nc[1].lineno, nc[1].col_offset)):
        if name in bound or name in found or name in FORBIDDEN_NAMES or name.startswith("_"):
            continue
        if hasattr(builtins, name):
            continue  # a real builtin the sandbox withholds on purpose: let it fail there
        # the innermost simple statement that contains the call, as the call site
        site = call.lineno
        end = getattr(call, "end_lineno", site) or site
        for st in statements:
            if isinstance(st, (ast.FunctionDef, ast.For, ast.While, ast.If, ast.Try)):
                continue
            if st.lineno <= call.lineno and (st.end_lineno or st.lineno) >= end:
                site, end = st.lineno, st.end_lineno or st.lineno
        snippet = "\n".join(ln.strip() for ln in lines[site - 1:end]).strip()
        found[name] = (name, call.lineno, snippet)
    return list(found.values())


def strip_benign_imports(code: str, available: set[str] | frozenset[str]) -> tuple[str, list[str]]:
    """Remove import lines that only re-import names the sandbox already provides.

    ``import numpy as np`` or ``from env_utils import get_obj_pos`` are harmless echoes of the
    prompt header; ``import os`` (or anything binding an unavailable name) is kept so that the
    sandbox rejects it.  Returns (code, removed lines).
    """
    try:
        tree = ast.parse(code)
    except (SyntaxError, ValueError):
        return code, []
    have = set(available) | SANDBOX_GLOBALS
    drop: list[tuple[int, int]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            ok = all(a.name in _BENIGN_MODULES and (a.asname or a.name).split(".")[0] in have
                     for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            star = [a.name for a in node.names] == ["*"]
            ok = node.level == 0 and (
                node.module in _STAR_MODULES if star else
                node.module in _BENIGN_MODULES and all((a.asname or a.name) in have for a in node.names))
        else:
            continue
        if ok:
            drop.append((node.lineno, node.end_lineno or node.lineno))
    if not drop:
        return code, []
    lines = code.splitlines()
    removed: list[str] = []
    for start, end in sorted(drop, reverse=True):
        removed[:0] = lines[start - 1:end]
        # keep line numbers stable: replace with 'pass' (imports may sit inside a block)
        indent = re.match(r"\s*", lines[start - 1]).group(0)  # type: ignore[union-attr]
        lines[start - 1:end] = [f"{indent}pass  # removed: {lines[start - 1].strip()}"] + [""] * (end - start)
    return "\n".join(lines) + "\n", removed


def function_defs(code: str, wanted: str, skip: set[str] | frozenset[str] = frozenset()) -> str:
    """Only the top-level function definitions of ``code``; one of them must be ``wanted``.

    Definitions of names in ``skip`` (the API, the LMPs, reserved names) are dropped: the model
    re-defining ``get_obj_pos`` or ``put_first_on_second`` must not replace the real one.
    """
    try:
        tree = ast.parse(code)
    except SyntaxError as exc:
        raise PlanSyntaxError(f"SyntaxError: {exc.msg} (in the function written for {wanted})",
                        line=exc.lineno, code=code) from None
    lines = code.splitlines()
    parts: list[str] = []
    names: list[str] = []
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name not in skip:
            start = min([d.lineno for d in node.decorator_list] + [node.lineno])
            parts.append("\n".join(lines[start - 1:node.end_lineno]))
            names.append(node.name)
    if wanted not in names:
        raise FunctionNotWritten(f"parse_function did not define '{wanted}' (defined: {names or 'nothing'})")
    return "\n\n".join(parts) + "\n\n"
