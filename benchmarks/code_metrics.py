"""Size and coupling figures of the source tree as JSON, for before/after comparisons of a clean-up.

Reads the files as text (AST), imports nothing of capmj, runs nothing of it:

- ``lines``: lines per module of ``src/capmj`` and ``task_plugins``, and those over 400;
- ``long_functions``: functions (and methods) over 80 lines, decorators excluded;
- ``import_cycles``: strongly connected components of the graph of *module-level* imports between
  ``capmj`` modules (an import inside a function, or under ``if TYPE_CHECKING``, does not run when
  the module loads and cannot make a cycle at import); ``from capmj.a import b`` is an edge to
  ``capmj.a.b`` when that is a module, else to ``capmj.a``; the goal is 0;
  ``import_cycles_counting_function_imports`` is the same over every import, where a function-level
  import hides a cycle of modules that need each other;
- ``function_imports``: imports inside function bodies (often a cycle being dodged), counted and listed;
- ``import_cycles_with_package_inits``: the same as ``import_cycles`` with the package
  ``__init__`` modules an import runs on its way (``from capmj.agents.api.values import x`` runs
  ``capmj/agents/api/__init__.py`` first): an edge to each package above the target that is not
  also above the importer, so two packages whose ``__init__`` re-export each other's modules form a
  cycle here even when no two modules do;
- ``modules_over_300``: the modules over 300 lines;
- ``agents``: the shape of ``capmj.agents``: its top-level modules, each sub-package (wing) with its
  modules and lines, and the reporters (``agents/report/``; before that package existed, the flat
  modules of the same concept: ``reporter*``, ``relation_*``, ``scene_*``, ``verdict``,
  ``confidence``, ``check_reads``, ``plan_check``) with their modules, lines and ``ast.parse`` calls;
- ``duplicates``: the pairs the ``duplicates`` tool lists over the whole checkout whose two sides
  are both in ``src/`` or ``task_plugins/`` (null when the tool is not installed).

    python benchmarks/code_metrics.py [--root .] > benchmarks/results/code_metrics_after.json
"""

from __future__ import annotations

import argparse
import ast
import json
import re
import shutil
import subprocess
from pathlib import Path

MAX_MODULE_LINES = 400
LONG_MODULE_LINES = 300
AGENTS = "capmj.agents"
REPORT = "capmj.agents.report"
FLAT_REPORT_PREFIXES = ("reporter", "relation_", "scene_")
FLAT_REPORT_NAMES = ("verdict", "confidence", "check_reads", "plan_check")
"""The reporter modules of ``capmj.agents`` while they were flat (before ``agents/report/``)."""
MAX_FUNCTION_LINES = 80
SOURCE_DIRS = ("src", "task_plugins")
_DUP_ROW = re.compile(r"^D\d+ (\S+?):(\d+-\d+) ~ (\S+?):(\d+-\d+)(.*)$")


def _modules(root: Path) -> dict[str, Path]:
    """Dotted module name -> file, for every ``.py`` under ``src/`` and ``task_plugins/``."""
    out: dict[str, Path] = {}
    for top in SOURCE_DIRS:
        for path in sorted((root / top).rglob("*.py")):
            rel = path.relative_to(root / top).with_suffix("")
            if {"prompts", "mjcf"} & set(rel.parts[:-1]):  # folders of templates and data, not modules
                continue
            parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
            out[".".join(parts)] = path
    return out


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _module_level_imports(tree: ast.Module) -> list[ast.Import | ast.ImportFrom]:
    """Imports that run when the module loads: top level, and inside top-level if/try blocks."""
    found: list[ast.Import | ast.ImportFrom] = []
    stack: list[ast.stmt] = list(tree.body)
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            found.append(node)
        elif isinstance(node, ast.If) and not _is_type_checking(node):
            stack.extend(node.body + node.orelse)
        elif isinstance(node, ast.Try):
            stack.extend(node.body + node.orelse + node.finalbody)
            for h in node.handlers:
                stack.extend(h.body)
    return found


def _targets(node: ast.Import | ast.ImportFrom, here: str, is_pkg: bool, mods: dict[str, Path]) -> set[str]:
    """The capmj modules an import statement loads (most specific known module per name)."""
    if isinstance(node, ast.Import):
        return {a.name for a in node.names if a.name in mods}
    base = node.module or ""
    if node.level:
        pkg = here.split(".") if is_pkg else here.split(".")[:-1]
        pkg = pkg[: len(pkg) - (node.level - 1)]
        base = ".".join(pkg + ([base] if base else []))
    out = set()
    for a in node.names:
        sub = f"{base}.{a.name}"
        if sub in mods:
            out.add(sub)
        elif base in mods:
            out.add(base)
    return out


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    comps: list[list[str]] = []
    counter = 0
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        comps.append(sorted(comp))
    return sorted(comps)


def _with_package_inits(graph: dict[str, set[str]], mods: dict[str, Path]) -> dict[str, set[str]]:
    """``graph`` plus, for each edge, the packages above its target that are not above its source."""
    out: dict[str, set[str]] = {}
    for src, targets in graph.items():
        above_src = {".".join(src.split(".")[:i]) for i in range(1, src.count(".") + 1)}
        edges = set(targets)
        for t in targets:
            for i in range(1, t.count(".") + 1):
                pkg = ".".join(t.split(".")[:i])
                if pkg in mods and pkg not in above_src and pkg != src:
                    edges.add(pkg)
        out[src] = edges
    return out


def _ast_parse_calls(tree: ast.Module) -> int:
    """Calls of ``ast.parse`` (or of ``parse`` imported from ``ast``)."""
    from_ast = {a.asname or a.name for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module == "ast"
                for a in n.names if a.name == "parse"}
    count = 0
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        if (isinstance(f, ast.Attribute) and f.attr == "parse" and isinstance(f.value, ast.Name) and f.value.id == "ast") \
                or (isinstance(f, ast.Name) and f.id in from_ast):
            count += 1
    return count


def _agents(mods: dict[str, Path], lines: dict[str, int], root: Path) -> dict:
    """Top-level modules, wings and the reporters of ``capmj.agents``."""
    inside = {name: path for name, path in mods.items() if name.startswith(AGENTS + ".")}
    top = sorted(name.split(".")[2] for name in inside if name.count(".") == 2 and inside[name].name != "__init__.py")
    wings: dict[str, dict] = {}
    for name, path in sorted(inside.items()):
        wing = name.split(".")[2]
        if path.name == "__init__.py" and name.count(".") == 2 or name.count(".") > 2:
            w = wings.setdefault(wing, {"modules": 0, "lines": 0})
            w["modules"] += 1
            w["lines"] += lines[str(path.relative_to(root))]
    report = {n: p for n, p in inside.items() if n == REPORT or n.startswith(REPORT + ".")}
    if not report:
        report = {n: p for n, p in inside.items() if n.count(".") == 2 and (
            n.split(".")[2].startswith(FLAT_REPORT_PREFIXES) or n.split(".")[2] in FLAT_REPORT_NAMES)}
    report_lines = {str(p.relative_to(root)): lines[str(p.relative_to(root))] for p in report.values()}
    return {
        "modules": len(inside),
        "lines": sum(lines[str(p.relative_to(root))] for p in inside.values()),
        "top_level_modules": {"count": len(top), "list": top},
        "wings": wings,
        "report": {
            "modules": len(report),
            "lines": sum(report_lines.values()),
            "ast_parse_calls": sum(_ast_parse_calls(ast.parse(p.read_text(encoding="utf-8"))) for p in report.values()),
            "lines_per_module": dict(sorted(report_lines.items())),
        },
    }


def _duplicates(root: Path) -> dict | None:
    tool = shutil.which("duplicates")
    if tool is None:
        return None
    text = subprocess.run([tool, "--repo", str(root), "--most", "200", "--seconds", "300"],
                          capture_output=True, text=True, check=False).stdout
    pairs = []
    for line in text.splitlines():
        m = _DUP_ROW.match(line)
        if m and all(p.split("/")[0] in SOURCE_DIRS for p in (m.group(1), m.group(3))):
            pairs.append(f"{m.group(1)}:{m.group(2)} ~ {m.group(3)}:{m.group(4)}{m.group(5)}")
    notes = [ln for ln in text.splitlines() if ln.startswith(("left out:", "incomplete:", "(+"))]
    return {"pairs": len(pairs), "list": pairs, "tool_notes": notes}


def measure(root: Path) -> dict:
    mods = _modules(root)
    lines: dict[str, int] = {}
    long_functions: list[dict] = []
    function_imports: dict[tuple[str, int], str] = {}
    graph: dict[str, set[str]] = {}
    graph_all: dict[str, set[str]] = {}
    for name, path in mods.items():
        rel = str(path.relative_to(root))
        text = path.read_text(encoding="utf-8")
        lines[rel] = len(text.splitlines())
        tree = ast.parse(text, filename=rel)
        is_pkg = path.name == "__init__.py"
        if name.split(".")[0] == "capmj":
            graph[name] = {t for n in _module_level_imports(tree)
                           for t in _targets(n, name, is_pkg, mods) if t != name and t.startswith("capmj")}
            every = [n for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom))]
            graph_all[name] = {t for n in every
                               for t in _targets(n, name, is_pkg, mods) if t != name and t.startswith("capmj")}
        for fn in ast.walk(tree):
            if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            n_lines = (fn.end_lineno or fn.lineno) - fn.lineno + 1
            if n_lines > MAX_FUNCTION_LINES:
                long_functions.append({"where": f"{rel}:{fn.lineno}", "function": fn.name, "lines": n_lines})
            for node in ast.walk(fn):
                if isinstance(node, (ast.Import, ast.ImportFrom)) and node.lineno > fn.lineno:
                    what = node.module if isinstance(node, ast.ImportFrom) else node.names[0].name
                    # ast.walk meets outer functions first: the innermost one names the place
                    function_imports[(rel, node.lineno)] = f"{fn.name}: {'.' * getattr(node, 'level', 0)}{what}"
    cycles, cycles_all = _cycles(graph), _cycles(graph_all)
    cycles_inits = _cycles(_with_package_inits(graph, mods))
    return {
        "modules": len(lines),
        "total_lines": sum(lines.values()),
        "lines_per_module": dict(sorted(lines.items())),
        "modules_over_400": {k: v for k, v in sorted(lines.items()) if v > MAX_MODULE_LINES},
        "functions_over_80": sorted(long_functions, key=lambda f: -f["lines"]),
        "import_cycles": {"count": len(cycles), "components": cycles},
        "import_cycles_counting_function_imports": {"count": len(cycles_all), "components": cycles_all},
        "import_cycles_with_package_inits": {"count": len(cycles_inits), "components": cycles_inits},
        "modules_over_300": {k: v for k, v in sorted(lines.items()) if v > LONG_MODULE_LINES},
        "agents": _agents(mods, lines, root),
        "function_level_imports": {"count": len(function_imports),
                                   "list": [f"{f}:{n} {w}" for (f, n), w in sorted(function_imports.items())]},
        "duplicates": _duplicates(root),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent,
                    help="the checkout to measure (default: this one)")
    args = ap.parse_args(argv)
    print(json.dumps(measure(args.root), indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
