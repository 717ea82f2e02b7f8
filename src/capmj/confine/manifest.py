"""Accepted means confined: a generated package records exactly what was checked, and runs only jailed.

The generator builds the package itself from the texts it sent to the checks and writes
:data:`MANIFEST` beside them: the sha256 of **every file** of the package, and for each task its
module, the facts it stated when checked (name, tags, docstring, methods — what listing shows
without running anything) and a sample goal.  Before capmj uses a task from a package that
carries a manifest, or whose distribution says it was written by an LLM (keyword
:data:`GENERATED_TAG`), :func:`verify` must find nothing: no file added or changed since
acceptance (a ``.pyc`` planted beside a module is an added file), each module passing the static
check again.  Files under ``__pycache__`` are not read by capmj at all (the jail compiles the
verified text), so an installer's bytecode is neither listed nor trusted.

Then :func:`confined_task` gives the task as a :class:`~capmj.confine.proxy.ConfinedTask`: the
verified text runs only in the jail.  Nothing here imports the package.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import json
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

from capmj.confine.names import import_findings, name_findings

if TYPE_CHECKING:  # the proxy pulls in numpy and the task protocol; verifying must stay cheap
    from capmj.confine.jail import Limits
    from capmj.confine.proxy import ConfinedTask

MANIFEST = "capmj-confinement.json"
GENERATED_TAG = "generated-by-llm"
"""The tag of every LLM-written task, and the keyword of the distributions that ship them."""
SCHEMA = 2
SKIPPED_DIRS = ("__pycache__",)
"""Directories of a package that capmj never reads (an installer's bytecode)."""


def sha256_text(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def manifest_text(package: str, files: Mapping[str, str], tasks: Mapping[str, Mapping[str, Any]]) -> str:
    """The manifest of a package built from ``files`` (relative path -> exact text) whose
    ``tasks`` map a task name to ``{"module": relative path, "facts": ..., "goal": ..., ...}``."""
    for name, entry in tasks.items():
        if entry.get("module") not in files:
            raise ValueError(f"task {name!r}: its module {entry.get('module')!r} is not a file of the package")
    body = {"schema": SCHEMA, "package": package, "files": {rel: sha256_text(t) for rel, t in sorted(files.items())},
            "tasks": {n: dict(tasks[n]) for n in sorted(tasks)}}
    return json.dumps(body, indent=2, sort_keys=True) + "\n"


def static_problems(code: str) -> list[str]:
    """The static confinement check (parse, imports, names) of one module, as one-line problems."""
    try:
        tree = ast.parse(code)
    except SyntaxError as e:
        return [f"SyntaxError: {e.msg} (line {e.lineno})"]
    except (RecursionError, MemoryError, ValueError) as e:  # nested too deeply, NUL bytes ...
        return [f"{type(e).__name__}: the module cannot be parsed"]
    return [str(f) for f in import_findings(tree) or name_findings(tree)]


def read_manifest(package_dir: Path) -> tuple[dict[str, Any] | None, str | None]:
    """The manifest of ``package_dir`` and ``None``, or ``None`` and why it cannot be used."""
    try:
        body = json.loads((package_dir / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        return None, (f"no readable {MANIFEST} in {package_dir} ({type(e).__name__}); the package was not "
                      "written by capmj.generate or was changed")
    if not isinstance(body, dict) or body.get("schema") != SCHEMA:
        schema = body.get("schema") if isinstance(body, dict) else None
        return None, (f"{MANIFEST} has schema {schema!r}, not {SCHEMA}: the package was written by an older capmj "
                      "whose checks ran generated code outside a jail; generate it again")
    if not isinstance(body.get("files"), dict) or not isinstance(body.get("tasks"), dict):
        return None, f"{MANIFEST} lacks its 'files' or 'tasks' table"
    return body, None


def _package_files(package_dir: Path) -> dict[str, Path]:
    return {p.relative_to(package_dir).as_posix(): p for p in sorted(package_dir.rglob("*"))
            if (p.is_file() or p.is_symlink()) and p.name != MANIFEST
            and not any(part in SKIPPED_DIRS for part in p.relative_to(package_dir).parts)}


def verify(package_dir: Path) -> list[str]:
    """Why the package at ``package_dir`` is not the package that was accepted (empty: it is)."""
    body, why = read_manifest(package_dir)
    if body is None:
        return [why or "unreadable manifest"]
    listed: dict[str, Any] = body["files"]
    found = _package_files(package_dir)
    problems = [f"{rel} is not in the manifest (added after acceptance)" for rel in sorted(set(found) - set(listed))]
    for rel, digest in sorted(listed.items()):
        path = found.get(rel)
        if path is None:
            problems.append(f"{rel} is listed in the manifest but missing")
            continue
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as e:
            problems.append(f"{rel} cannot be read as text ({type(e).__name__})")
            continue
        if sha256_text(text) != digest:
            problems.append(f"{rel} was edited after acceptance (sha256 differs from the manifest)")
        if rel.endswith(".py"):
            problems += [f"{rel}: {p}" for p in static_problems(text)]
    return problems


def _package_dir(entry: metadata.EntryPoint) -> Path | None:
    """The directory of the entry point's top-level package, found without importing it."""
    top = entry.value.split(":")[0].split(".")[0]
    try:
        spec = importlib.util.find_spec(top)  # a top-level name: nothing is executed
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(list(spec.submodule_search_locations)[0])


def _generated(entry: metadata.EntryPoint) -> bool:
    dist = getattr(entry, "dist", None)
    keywords = (dist.metadata.get("Keywords") or "") if dist is not None else ""
    return GENERATED_TAG in keywords.replace(",", " ").split()


def is_generated(entry: metadata.EntryPoint) -> bool:
    """Whether the entry point's task is LLM-written (the distribution says so, or it ships a manifest)."""
    pkg = _package_dir(entry)
    return _generated(entry) or (pkg is not None and (pkg / MANIFEST).is_file())


def _inspect(entry: metadata.EntryPoint) -> tuple[list[str] | None, Path | None, dict[str, Any] | None]:
    """One verification of ``entry``'s package: ``(problems, package dir, manifest)``; ``problems``
    is ``None`` for a package that is not generated, and the rest is set only when it is ``[]``."""
    if not is_generated(entry):
        return None, None, None
    pkg = _package_dir(entry)
    if pkg is None:
        return [f"cannot locate the package of {entry.value!r} to check it"], None, None
    problems = verify(pkg)
    if problems:
        return problems, None, None
    body, _ = read_manifest(pkg)
    assert body is not None
    module, _, attr = entry.value.partition(":")
    task = body["tasks"].get(entry.name)
    rel = module.split(".", 1)[1].replace(".", "/") + ".py" if "." in module else ""
    if not isinstance(task, dict) or task.get("module") != rel or attr.strip() != "TASK":
        return [f"the entry point {entry.name} = {entry.value!r} is not the task {MANIFEST} accepted"], None, None
    return [], pkg, body


def confinement_problems(entry: metadata.EntryPoint) -> list[str] | None:
    """``None`` for a package that is not generated; else what fails its confinement (``[]``: nothing)."""
    return _inspect(entry)[0]


def confined_task(entry: metadata.EntryPoint, limits: Limits | None = None) -> ConfinedTask:
    """The verified generated task of ``entry``, runnable only in the jail (starts no process yet).

    Raises :class:`~capmj.errors.UnverifiedPackage` when the package fails :func:`confinement_problems`.
    """
    from capmj.confine.jail import Limits
    from capmj.confine.proxy import ConfinedTask, ModuleSource, TaskFacts
    from capmj.errors import UnverifiedPackage

    problems, pkg, body = _inspect(entry)
    if problems is None:
        problems = [f"{entry.value!r} is not an LLM-written task package"]
    if problems or pkg is None or body is None:
        raise UnverifiedPackage(problems)
    task = dict(body["tasks"][entry.name])
    text = (pkg / task["module"]).read_text(encoding="utf-8")
    if sha256_text(text) != body["files"][task["module"]]:  # changed between the check and this read
        raise UnverifiedPackage([f"{task['module']} changed while it was being verified"])
    module = entry.value.partition(":")[0]
    goal = task.get("goal") if isinstance(task.get("goal"), str) else None
    return ConfinedTask(ModuleSource(module, text), limits or Limits(), expected=TaskFacts.from_dict(task.get("facts")),
                        sample_goal=goal)


__all__ = ["GENERATED_TAG", "MANIFEST", "SCHEMA", "confined_task", "confinement_problems", "is_generated",
           "manifest_text", "read_manifest", "sha256_text", "static_problems", "verify"]
