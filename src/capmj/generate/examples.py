"""Library tasks shown to the generator as a generated task must be written: self-contained.

Why: every installed task imports helpers from its own package (``capmj_tasks.common``,
``capmj_tasks.structures``), which a generated task may not import, and a model copies the imports
of the examples it is shown whatever the prompt says (``docs/generate.md`` has the run where this
rejected every candidate).  So the writing turn shows each example *as if it had been written under the same rules*: every
import outside the task API is replaced by the definitions it provided, copied from the helper
module's source (recursively, only what is used), constants of modules outside the API become
literals, and the library's own tags become the generated tag.

The view is checked with the generator's own static checks; an example that cannot be made
self-contained (it needs a function of a module outside the API that is not plain Python source)
has no view and is not offered.  ``tests/test_generate_examples.py`` runs every view and compares
its scenes and verdicts with the installed task's.
"""

from __future__ import annotations

import ast
import importlib
import inspect
from dataclasses import dataclass, field
from functools import cache

from capmj.confine.names import import_findings
from capmj.errors import TaskError
from capmj.generate.config import GENERATED_TAG
from capmj.tasks.builtin import BENCHMARK_TAG, EXTENDED_TAG

RETAG = {BENCHMARK_TAG: GENERATED_TAG, EXTENDED_TAG: GENERATED_TAG}
"""Tags of the hand-written library shown as the tag every generated task must carry."""

MAX_DEPTH = 6
"""Helper modules followed through at most this many re-exports (a guard, not a limit met in practice)."""

_Binding = tuple[str, str | None]
"""What a top-level name is bound to: ``(module, member)`` for an import, ``("def:" + module, name)``
for a definition copied from ``module``."""


class NotSelfContained(TaskError):
    """A library task cannot be shown importing only the task API (the reason is the message);
    it is then not offered as an example."""


@dataclass(frozen=True)
class _Module:
    """A helper module's source read as an AST: its top-level definitions and imports by bound name."""

    name: str
    lines: tuple[str, ...]
    defs: dict[str, ast.stmt]
    imports: dict[str, _Binding]


@cache
def _module(name: str) -> _Module:
    try:
        source = inspect.getsource(importlib.import_module(name))
    except (ImportError, OSError, TypeError) as e:
        raise NotSelfContained(f"the source of {name} is not readable: {e}") from e
    tree = ast.parse(source)
    defs: dict[str, ast.stmt] = {}
    for stmt in tree.body:
        if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            defs[stmt.name] = stmt
        elif isinstance(stmt, ast.Assign):
            for t in stmt.targets:
                if isinstance(t, ast.Name):
                    defs[t.id] = stmt
        elif isinstance(stmt, ast.AnnAssign) and isinstance(stmt.target, ast.Name) and stmt.value is not None:
            defs[stmt.target.id] = stmt
    return _Module(name, tuple(source.splitlines()), defs, _imports(tree, name))


def _imports(tree: ast.Module, module: str) -> dict[str, _Binding]:
    out: dict[str, _Binding] = {}
    for stmt in tree.body:
        if isinstance(stmt, ast.ImportFrom) and stmt.module and stmt.level == 0 and stmt.module != "__future__":
            for a in stmt.names:
                out[a.asname or a.name] = (stmt.module, a.name)
        elif isinstance(stmt, ast.Import):
            for a in stmt.names:
                if a.asname is None and "." in a.name:
                    raise NotSelfContained(f"{module} imports {a.name} without a name to bind")
                out[a.asname or a.name] = (a.name, None)
    return out


def _import_text(bound: str, b: _Binding) -> str:
    module, member = b
    if member is None:
        return f"import {module}" + ("" if bound == module else f" as {bound}")
    return f"from {module} import {member}" + ("" if bound == member else f" as {bound}")


def _allowed(bound: str, b: _Binding) -> bool:
    return not import_findings(ast.parse(_import_text(bound, b)))


def _free_names(stmt: ast.stmt) -> list[str]:
    """Names a statement reads, in order of appearance (locals included: they resolve to nothing)."""
    seen: dict[str, None] = {}
    for node in ast.walk(stmt):
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load):
            seen.setdefault(node.id, None)
    return list(seen)


def _is_literal(value: object) -> bool:
    if isinstance(value, (str, int, float, bool)) or value is None:
        return True
    return isinstance(value, (tuple, frozenset)) and all(_is_literal(v) for v in value)


def _literal(value: object) -> str:
    if isinstance(value, str):
        return repr(RETAG.get(value, value))
    if isinstance(value, frozenset):
        return "frozenset({" + ", ".join(sorted(_literal(v) for v in value)) + "})" if value else "frozenset()"
    return repr(value)


def _value(module: str, name: str | None) -> object:
    return getattr(importlib.import_module(module), name, None) if name else None


def _canonical(b: _Binding, depth: int = 0) -> _Binding:
    """Where a binding's value really comes from: an allowed import, a literal constant, or a
    definition in some module's source (re-exports followed); raises when it is none of these."""
    module, member = b
    if module.startswith("literal:"):
        return b
    if module.startswith("def:"):
        return ("literal:" + module[4:], member) if _is_literal(_value(module[4:], member)) else b
    if _allowed(member or module, b):
        return b
    if member is None:
        raise NotSelfContained(f"import {module} is outside the task API")
    if depth > MAX_DEPTH:
        raise NotSelfContained(f"{module}.{member} is re-exported more than {MAX_DEPTH} times")
    if _is_literal(_value(module, member)):
        return ("literal:" + module, member)
    m = _module(module)
    if member in m.defs:
        return ("def:" + module, member)
    if member in m.imports:
        return _canonical(m.imports[member], depth + 1)
    raise NotSelfContained(f"{module}.{member} is neither source nor a literal constant")


def _short_docstrings(stmt: ast.stmt, lines: list[str], first: int) -> list[str]:
    """``lines`` (the statement's source from line ``first``) with every multi-line docstring cut to
    its first line: the examples are read by small models, and the copied helpers' prose is long."""
    out = list(lines)
    docs = []
    for node in ast.walk(stmt):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and node.body:
            d = node.body[0]
            if (isinstance(d, ast.Expr) and isinstance(d.value, ast.Constant) and isinstance(d.value.value, str)
                    and d.end_lineno and d.end_lineno > d.lineno):
                docs.append(d)
    for d in sorted(docs, key=lambda n: -n.lineno):
        text = inspect.cleandoc(d.value.value).splitlines()[0].rstrip()  # type: ignore[attr-defined]
        indent = out[d.lineno - first][: d.col_offset]
        out[d.lineno - first: (d.end_lineno or d.lineno) - first + 1] = [f'{indent}"""{text}"""']
    return out


@dataclass
class _View:
    """What the example's namespace binds (canonically), and the code added to provide it."""

    bound: dict[str, _Binding]
    imports: list[tuple[str, _Binding]] = field(default_factory=list)
    constants: list[str] = field(default_factory=list)
    copied: list[str] = field(default_factory=list)
    """Copied definitions, each after the ones it needs (a class's base before the class)."""
    modules: list[str] = field(default_factory=list)

    def bind(self, name: str, b: _Binding) -> None:
        c = _canonical(b)
        if name in self.bound:
            if self.bound[name] != c:
                raise NotSelfContained(f"{name!r} would mean both {self.bound[name]} and {c}")
            return
        kind, member = c
        if kind.startswith("literal:"):
            self.bound[name] = c
            self.constants.append(f"{name} = {_literal(_value(kind[8:], member))}")
        elif kind.startswith("def:"):
            if member != name:
                raise NotSelfContained(f"{member} of {kind[4:]} is imported under another name, {name!r}")
            self._copy(name, _module(kind[4:]))
        else:
            self.bound[name] = c
            self.imports.append((name, c))

    def _copy(self, name: str, m: _Module) -> None:
        stmt = m.defs[name]
        for n, s in m.defs.items():  # ``a = b = ...`` binds both
            if s is stmt:
                self.bound[n] = ("def:" + m.name, n)
        for ref in _free_names(stmt):  # any other name is a local, a parameter or a builtin
            if ref in m.defs:
                self.bind(ref, ("def:" + m.name, ref))
            elif ref in m.imports:
                self.bind(ref, m.imports[ref])
        start = min([stmt.lineno, *(d.lineno for d in getattr(stmt, "decorator_list", []))])
        text = _short_docstrings(stmt, list(m.lines[start - 1:stmt.end_lineno or stmt.lineno]), start)
        self.copied.append("\n".join(text))
        if m.name not in self.modules:
            self.modules.append(m.name)


def self_contained(source: str) -> str:
    """``source`` (a task module) with every import outside the task API replaced by what it provided.

    Raises :class:`NotSelfContained` when that is impossible.  A module that already imports only
    the task API comes back unchanged.
    """
    tree = ast.parse(source)
    lines = source.splitlines()
    own = _imports(tree, "<example>")
    view = _View(bound={})
    for stmt in tree.body:  # the example's own definitions: a copied helper must not shadow one
        for n in _top_level_names(stmt):
            view.bound[n] = ("def:<example>", n)
    statements = [s for s in tree.body if isinstance(s, (ast.Import, ast.ImportFrom))
                  and not (isinstance(s, ast.ImportFrom) and s.module == "__future__")]
    refused = []
    for stmt in statements:
        names = [a.asname or a.name for a in stmt.names]
        if all(_allowed(n, own[n]) for n in names):
            view.bound.update({n: own[n] for n in names})
        else:
            refused.append((stmt, names))
    if refused:
        for _, names in refused:
            for n in names:
                view.bind(n, own[n])
        drop = {i for stmt, _ in refused for i in range(stmt.lineno, (stmt.end_lineno or stmt.lineno) + 1)}
        last = max(s.end_lineno or s.lineno for s in statements)
        block = [*_grouped(view.imports), "", "",
                 f"# ----- helpers of {' and '.join(view.modules)}, copied here: a generated task may",
                 "# import only the task API, so it defines what it needs itself", *view.constants]
        for text in view.copied:
            block += ["", "", text] if text.startswith(("def ", "class ", "@")) else [text]
        head = [line for i, line in enumerate(lines[:last], start=1) if i not in drop]
        source = "\n".join([*head, *block, *lines[last:]]).rstrip() + "\n"
    bad = import_findings(ast.parse(source))
    if bad:
        raise NotSelfContained("; ".join(map(str, bad)))
    return source


def _grouped(imports: list[tuple[str, _Binding]]) -> list[str]:
    """Import lines, one ``from M import a, b`` per module in order of first use."""
    plain = [_import_text(n, b) for n, b in imports if b[1] is None]
    by: dict[str, list[str]] = {}
    for n, (module, member) in imports:
        if member is not None:
            by.setdefault(module, []).append(member if n == member else f"{member} as {n}")
    return plain + [f"from {m} import {', '.join(names)}" for m, names in by.items()]


def _top_level_names(stmt: ast.stmt) -> list[str]:
    if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return [stmt.name]
    if isinstance(stmt, ast.Assign):
        return [t.id for t in stmt.targets if isinstance(t, ast.Name)]
    if isinstance(stmt, ast.AnnAssign) and isinstance(stmt.target, ast.Name):
        return [stmt.target.id]
    return []


__all__ = ["NotSelfContained", "RETAG", "self_contained"]
