"""The static confinement check of generated task code: names, not modules (issue #25).

Reads the code as an AST and never runs it.  Three rules close the doors a module allow-list
leaves open:

1. **Imports** name only modules of :data:`~capmj.confine.allowlist.IMPORTABLE`, and
   ``from M import N`` only members :func:`~capmj.confine.allowlist.members` lists (or an
   allowed submodule): ``from capmj.tasks import registry`` is refused although ``capmj.tasks``
   is allowed.
2. **Module objects** are followed through every attribute: a name bound to a module may only
   start a dotted path that ends at a listed member (``np.linalg.norm``); ``typing.sys``,
   ``np.f2py``, a module used as a value (``m = np``), rebound or assigned into
   (``P.in_zone = ...``) is refused.
3. **Doors by name**: the modules and functions that reach the operating system or the
   interpreter (``os``, ``sys``, ``subprocess``, ``importlib``, ``builtins``, ``ctypes`` …) are
   refused as identifiers and attributes anywhere, as are dunder attributes, reflection and I/O
   builtins, and the attributes of frames, tracebacks, coroutines and file writers — also where a
   ``match`` class pattern reads them (``case object(__globals__=g)``) or a format string does
   (``"{0.__globals__}".format(f)``).

Each finding names the line and the door, so a repair prompt can say exactly what to change.
"""

from __future__ import annotations

import ast
import string
from dataclasses import dataclass

from capmj.confine.allowlist import IMPORTABLE, is_module, members

DOORS = frozenset({
    "os", "sys", "subprocess", "importlib", "builtins", "__builtins__", "ctypes", "ctypeslib", "socket", "shutil",
    "pathlib", "io", "posix", "_posixsubprocess", "pty", "signal", "multiprocessing", "threading", "_thread",
    "concurrent", "asyncio", "pickle", "marshal", "shelve", "mmap", "resource", "gc", "inspect", "runpy", "pkgutil",
    "tempfile", "glob", "urllib", "http", "webbrowser", "f2py", "distutils", "setuptools", "site", "sysconfig",
    "atexit", "faulthandler", "modules", "system", "popen", "fork", "forkpty", "execv", "execve", "spawnv",
    "posix_spawn", "environ", "import_module", "__import__", "__loader__", "__spec__",
})
"""Names of modules and calls that reach the OS or the import system; no task needs one."""

FORBIDDEN_CALLS = frozenset({
    "open", "exec", "eval", "compile", "__import__", "globals", "locals", "vars", "input", "breakpoint",
    "getattr", "setattr", "delattr", "exit", "quit", "memoryview", "help",
})
"""Builtins a task has no business calling: I/O, dynamic code, reflection that escapes the AST check."""

FORBIDDEN_ATTRIBUTES = frozenset({
    "tofile", "dump", "dumps", "ctypes", "load", "loads", "save", "savez", "savez_compressed",
    "savetxt", "loadtxt", "genfromtxt", "fromfile", "memmap", "gi_frame", "gi_code", "ag_frame",
    "cr_frame", "f_globals", "f_locals", "f_builtins", "f_back", "f_code", "f_trace",
    "tb_frame", "tb_next", "mro", "cr_code", "ag_code", "cr_await", "gi_yieldfrom", "co_code", "co_consts",
})
"""Rejected on any object: file I/O, pickling, raw memory and frame access (shared with the plan
sandbox, :mod:`capmj.agents.sandbox.checks`)."""

DUNDER_OK = frozenset({"__init__", "__post_init__", "__repr__", "__name__", "__doc__", "__future__"})


@dataclass(frozen=True)
class Finding:
    """One refused construct: its line and what to say about it."""

    line: int
    message: str

    def __str__(self) -> str:
        return f"line {self.line}: {self.message}"


def _import_findings(tree: ast.AST, aliases: dict[str, str]) -> list[Finding]:
    """Rule 1; fills ``aliases`` (local name -> module path) for rule 2."""
    bad = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name not in IMPORTABLE:
                    bad.append(Finding(node.lineno, f"import of {a.name!r}"))
                elif a.asname:
                    aliases[a.asname] = a.name
                else:
                    aliases[a.name.split(".")[0]] = a.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom):
            mod = node.module or ""
            if node.level:
                bad.append(Finding(node.lineno, "relative import"))
                continue
            if mod not in IMPORTABLE and not is_module(mod):
                bad.append(Finding(node.lineno, f"import from {mod!r}"))
                continue
            for a in node.names:
                path = f"{mod}.{a.name}"
                if is_module(path):
                    aliases[a.asname or a.name] = path
                elif a.name not in members(mod):
                    hint = "; draw from the rng argument" if mod == "numpy.random" else ""
                    bad.append(Finding(node.lineno, f"{path} is not part of the task API{hint}"))
    return bad


def import_findings(tree: ast.AST) -> list[Finding]:
    """Rule 1 alone: every import that names a module or member outside the allow-list."""
    return _import_findings(tree, {})


def _parents(tree: ast.AST) -> dict[ast.AST, ast.AST]:
    return {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}


def _follow(name: ast.Name, module: str, parents: dict[ast.AST, ast.AST]) -> Finding | None:
    """Rule 2 for one use of a module alias: the dotted path must end at a listed member."""
    path, written = module, name.id
    node: ast.expr = name
    while True:
        parent = parents.get(node)
        if not (isinstance(parent, ast.Attribute) and parent.value is node):
            return Finding(name.lineno, f"{written!r} is the module {path} used as a value; use its listed names")
        path, written = f"{path}.{parent.attr}", f"{written}.{parent.attr}"
        if isinstance(parent.ctx, (ast.Store, ast.Del)):
            return Finding(name.lineno, f"{written} assigns into the module {path.rsplit('.', 1)[0]}; "
                                        "a task must not change the modules it uses")
        if is_module(path):
            node = parent
            continue
        owner, attr = path.rsplit(".", 1)
        if attr in members(owner):
            return None
        hint = "; draw from the rng argument" if owner == "numpy.random" else ""
        return Finding(name.lineno, f"{written} ({path}) is not part of the task API{hint}")


def _format_finding(call: ast.Call) -> Finding | None:
    """``"{0.attr}".format(x)`` / ``format_map``: a replacement field that reads an attribute or an
    item reaches what no attribute check sees (``{0.__globals__[os]}``)."""
    f = call.func
    if not (isinstance(f, ast.Attribute) and f.attr in ("format", "format_map")):
        return None
    if not (isinstance(f.value, ast.Constant) and isinstance(f.value.value, str)):
        return Finding(call.lineno, f".{f.attr}() on a computed string is not allowed in a task; use an f-string")
    try:
        fields = [name for _, name, _, _ in string.Formatter().parse(f.value.value) if name]
    except ValueError:
        return Finding(call.lineno, "a malformed format string")
    deep = [n for n in fields if "." in n or "[" in n]
    return Finding(call.lineno, f"the format field {{{deep[0]}}} reads an attribute or item; use an f-string") if deep else None


def name_findings(tree: ast.AST) -> list[Finding]:
    """Rules 2 and 3 (run after :func:`import_findings` found nothing)."""
    aliases: dict[str, str] = {}
    _import_findings(tree, aliases)
    parents = _parents(tree)
    bad = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            if node.id in DOORS:
                bad.append(Finding(node.lineno, f"{node.id!r} is a door to the operating system"))
            elif node.id in FORBIDDEN_CALLS:
                bad.append(Finding(node.lineno, f"{node.id!r} is not allowed in a task"))
            elif node.id in aliases:
                if isinstance(node.ctx, (ast.Store, ast.Del)):
                    bad.append(Finding(node.lineno, f"{node.id!r} names the module {aliases[node.id]}; do not rebind it"))
                elif (f := _follow(node, aliases[node.id], parents)) is not None:
                    bad.append(f)
        elif isinstance(node, ast.Attribute):
            a = node.attr
            if a in DOORS:
                bad.append(Finding(node.lineno, f"attribute {a!r} is a door to the operating system"))
            elif (a.startswith("__") and a not in DUNDER_OK) or a in FORBIDDEN_ATTRIBUTES:
                bad.append(Finding(node.lineno, f"attribute {a!r} is not allowed in a task"))
        elif isinstance(node, ast.MatchClass):  # `case C(attr=p)` reads C's attribute `attr`
            for a in node.kwd_attrs:
                if a in DOORS or (a.startswith("__") and a not in DUNDER_OK) or a in FORBIDDEN_ATTRIBUTES:
                    bad.append(Finding(node.lineno, f"the class pattern reads the attribute {a!r}, not allowed in a task"))
        elif isinstance(node, ast.Call) and (f := _format_finding(node)) is not None:
            bad.append(f)
        elif isinstance(node, ast.alias):
            for part in (node.asname or "", *node.name.split(".")):
                if part in DOORS:
                    bad.append(Finding(getattr(node, "lineno", 0), f"{part!r} is a door to the operating system"))
    return bad


__all__ = ["DOORS", "DUNDER_OK", "FORBIDDEN_ATTRIBUTES", "FORBIDDEN_CALLS", "Finding", "import_findings",
           "name_findings"]
