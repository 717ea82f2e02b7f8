"""``capmj.agents`` is built of wings, one concept each, that depend on each other in one direction.

Read from the source as an AST (nothing is imported to find an import), every import of a module
counts wherever it is written: at the top, in a function, under ``if TYPE_CHECKING``.

- The wings are layered: ``sandbox`` (running untrusted code), ``api`` (the planner API), ``lmp``
  (asking an LLM for code), ``report`` (the reporters), ``llm_agent`` (the LLM agent); a wing
  imports only the wings before it and the top-level modules of ``agents/``.
- ``agents/report/`` imports neither the agent nor its loop policy nor the planner (nothing of
  ``agents/llm_agent/``), and only the agent, the loop policy, ``judge/`` and ``report/`` itself
  import it: a reporter is judged on its own (``python -m capmj.bench judge``) exactly as the
  closed loop calls it.
- The sandbox's private names stay in the module that defines them: no module, in the sandbox or
  outside it, imports a ``_name`` from a sandbox module.
- Each wing has a curated ``__init__.py`` (an explicit ``__all__``), and ``agents/`` itself keeps a
  small top level; every reporter of :data:`capmj.agents.choices.REPORTER_TABLE` lives in
  ``agents/report/`` and satisfies the :class:`~capmj.agents.report.Reporter` protocol.
"""

from __future__ import annotations

import ast
import importlib
import inspect
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SRC = ROOT / "src"
AGENTS = SRC / "capmj" / "agents"

WINGS = ("sandbox", "api", "lmp", "report", "llm_agent")
"""The wings of ``capmj.agents``, lowest first."""
MAX_TOP_LEVEL = 12
"""Modules ``agents/`` may hold besides its wings (a new module goes in a wing, or here with a reason)."""
REPORT = "capmj.agents.report"
AGENT_WING = "capmj.agents.llm_agent"
MAY_IMPORT_REPORT = ("capmj.agents.llm_agent.agent", "capmj.agents.llm_agent.loop_policy", "capmj.judge", REPORT)
"""The agent, its loop policy, the judge and the reporters themselves."""


def _name(path: Path) -> str:
    rel = path.relative_to(SRC).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts)


def _modules(top: Path = SRC / "capmj") -> dict[str, Path]:
    return {_name(p): p for p in sorted(top.rglob("*.py")) if not {"prompts", "mjcf"} & set(p.relative_to(SRC).parts)}


def _within(name: str, package: str) -> bool:
    return name == package or name.startswith(package + ".")


def imports(path: Path, source: str | None = None) -> list[tuple[int, str, tuple[str, ...]]]:
    """Every import of a module: ``(line, imported module, names taken from it)``, relative ones resolved."""
    tree = ast.parse(source if source is not None else path.read_text(encoding="utf-8"))
    here = _name(path).split(".") if path.is_relative_to(SRC) else []
    package = here if path.name == "__init__.py" else here[:-1]
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name, ()) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package[: len(package) - node.level + 1] + ([base] if base else []))
            out.append((node.lineno, base, tuple(a.name for a in node.names)))
    return sorted(out)


def imported_modules(path: Path) -> set[str]:
    """Every capmj module or package an import of ``path`` names (``from a import b``: ``a`` and ``a.b``)."""
    out = set()
    for _, module, names in imports(path):
        out.add(module)
        out.update(f"{module}.{n}" for n in names)
    return {m for m in out if _within(m, "capmj")}


def test_the_reader_sees_every_kind_of_import() -> None:
    source = ("import capmj.agents.report.text\nfrom typing import TYPE_CHECKING\n"
              "if TYPE_CHECKING:\n    from capmj.agents.llm_agent import agent\n"
              "def f():\n    from capmj.agents.sandbox.facades import _Facade\n"
              "from . import verdict\n")
    found = imports(AGENTS / "report" / "text.py", source)
    assert [(line, module) for line, module, _ in found] == [
        (1, "capmj.agents.report.text"), (2, "typing"), (4, "capmj.agents.llm_agent"),
        (6, "capmj.agents.sandbox.facades"), (7, "capmj.agents.report")]
    assert found[2][2] == ("agent",) and found[3][2] == ("_Facade",)


def _wing(module: str) -> str | None:
    parts = module.split(".")
    return parts[2] if len(parts) > 2 and parts[:2] == ["capmj", "agents"] and parts[2] in WINGS else None


@pytest.mark.parametrize("wing", WINGS)
def test_a_wing_imports_only_the_wings_below_it(wing: str) -> None:
    below = set(WINGS[: WINGS.index(wing) + 1])
    bad = [f"{_name(p)} imports {m}" for name, p in _modules(AGENTS / wing).items()
           for m in sorted(imported_modules(p)) if (_wing(m) or wing) not in below]
    assert not bad, f"agents/{wing}/ reaches up the wings {WINGS}: {bad}"


def test_the_reporters_import_neither_the_agent_nor_its_loop_policy_nor_the_planner() -> None:
    bad = [f"{name} imports {m}" for name, p in _modules(AGENTS / "report").items()
           for m in sorted(imported_modules(p)) if _within(m, AGENT_WING)]
    assert not bad, bad


def test_only_the_agent_its_loop_policy_the_judge_and_the_reporters_import_the_reporters() -> None:
    bad = [f"{name} imports {m}" for name, p in _modules().items()
           if not any(_within(name, ok) for ok in MAY_IMPORT_REPORT)
           for m in sorted(imported_modules(p)) if _within(m, REPORT)]
    assert not bad, bad


def test_no_module_imports_a_private_name_of_the_sandbox() -> None:
    files = [*SRC.rglob("*.py"), *(ROOT / "tests").rglob("*.py"), *(ROOT / "benchmarks").glob("*.py"),
             *(ROOT / "task_plugins").rglob("*.py")]
    bad = []
    for path in sorted(files):
        try:
            found = imports(path)
        except SyntaxError:  # fixtures of broken code (tests/generator_candidates ...)
            continue
        for line, module, names in found:
            private = [n for n in names if n.startswith("_") and not n.startswith("__")]
            if private and _within(module, "capmj.agents.sandbox"):
                bad.append(f"{path.relative_to(ROOT)}:{line} imports {', '.join(private)} from {module}")
    assert not bad, bad


def test_each_wing_has_a_curated_init_and_the_top_level_is_small() -> None:
    for wing in WINGS:
        tree = ast.parse((AGENTS / wing / "__init__.py").read_text(encoding="utf-8"))
        assert ast.get_docstring(tree), f"agents/{wing}/__init__.py says what the wing holds"
        assert any(isinstance(n, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__" for t in n.targets)
                   for n in tree.body), f"agents/{wing}/__init__.py has an explicit __all__"
    packages = sorted(p.name for p in AGENTS.iterdir() if (p / "__init__.py").is_file())
    assert packages == sorted(WINGS), f"every sub-package of agents/ is a wing of WINGS: {packages}"
    top = sorted(p.stem for p in AGENTS.glob("*.py") if p.name != "__init__.py")
    assert len(top) <= MAX_TOP_LEVEL, f"agents/ holds {len(top)} modules ({top}): put the new one in a wing"


def test_every_reporter_of_the_table_lives_in_report_and_is_a_reporter() -> None:
    from capmj.agents.choices import REPORTER_PROMPTS, REPORTER_TABLE, REPORTERS
    from capmj.agents.report import Reporter
    from capmj.agents.report.registry import load_reporter

    assert REPORTERS == tuple(REPORTER_TABLE) and REPORTER_PROMPTS == tuple(REPORTER_TABLE["text"])
    protocol = {n for n in dir(Reporter) if not n.startswith("_")} | set(Reporter.__annotations__)
    for mode, prompts in REPORTER_TABLE.items():
        for prompt, entry in prompts.items():
            assert _within(entry.target.partition(":")[0], REPORT), entry.target
            cls = load_reporter(entry.target)
            assert inspect.isclass(cls) and importlib.import_module(cls.__module__) is not None
            reporter = cls(None)
            missing = {n for n in protocol if not hasattr(reporter, n)}
            assert not missing and reporter.mode == mode, (mode, prompt, missing)


def test_the_architecture_doc_names_every_module_of_agents_in_its_folder() -> None:
    rows = {line.split("|")[1].strip().strip("`"): line for line in
            (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8").splitlines()
            if line.startswith("| `src/capmj/agents/")}
    missing = []
    for path in sorted(AGENTS.rglob("*.py")):
        if path.name == "__init__.py":
            continue
        rel = path.relative_to(SRC.parent)
        folder = str(rel.parent) + "/"
        while folder not in rows and folder != "src/capmj/agents/":  # a sub-folder is named in its wing's row
            folder = str(Path(folder).parent) + "/"
        if f"`{path.name}`" not in rows.get(folder, ""):
            missing.append(str(rel))
    assert not missing, f"docs/architecture.md does not name these in their folder's row: {missing}"


def test_the_docs_list_the_reporters_of_the_table() -> None:
    """Where a doc spells out the choices (``--reporter none|text|vlm``), they are the table's."""
    import re

    from capmj.agents.choices import REPORTER_PROMPTS, REPORTERS

    want = {"--reporter": list(REPORTERS), "--reporter-prompt": list(REPORTER_PROMPTS)}
    found = 0
    for doc in sorted((ROOT / "docs").glob("*.md")) + [ROOT / "README.md", ROOT / "prompts" / "README.md"]:
        for m in re.finditer(r"(--reporter(?:-prompt)?) ([a-z]+(?:\\?\|[a-z]+)+)", doc.read_text(encoding="utf-8")):
            found += 1
            names = m.group(2).replace("\\|", "|").split("|")
            assert names == want[m.group(1)], f"{doc.relative_to(ROOT)}: {m.group(0)} (the table: {want[m.group(1)]})"
    assert found >= 4
