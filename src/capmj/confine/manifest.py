"""Accepted means confined: a generated package records what was checked, and is re-checked on load.

The generator writes :data:`MANIFEST` into the package it builds: every module's sha256 and how
the module was checked.  Before capmj imports a task from a package that carries a manifest, or
whose distribution says it was written by an LLM (keyword :data:`GENERATED_TAG`), the registry
calls :func:`confinement_problems`: every ``.py`` file of the package must be listed, unchanged
since acceptance, and pass the static check again.  A module edited after acceptance (by hand,
by a later tool, by an attacker with write access to site-packages) is refused before it runs.

Only metadata and files are read here; nothing of the package is imported.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import json
from importlib import metadata
from pathlib import Path
from typing import Any, Mapping

from capmj.confine.names import import_findings, name_findings

MANIFEST = "capmj-confinement.json"
GENERATED_TAG = "generated-by-llm"
"""The tag of every LLM-written task, and the keyword of the distributions that ship them."""
SCHEMA = 1


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def manifest_text(modules: Mapping[str, Mapping[str, Any]], package_dir: Path) -> str:
    """The manifest of ``package_dir``: ``modules`` (file name -> how it was checked) with each
    file's sha256 added, plus every other ``.py`` file of the package (e.g. ``__init__.py``)."""
    entries: dict[str, dict[str, Any]] = {}
    for path in sorted(package_dir.rglob("*.py")):
        rel = path.relative_to(package_dir).as_posix()
        entries[rel] = {**modules.get(rel, {"written_by": "capmj.generate"}), "sha256": sha256(path)}
    return json.dumps({"schema": SCHEMA, "modules": entries}, indent=2, sort_keys=True) + "\n"


def static_problems(code: str) -> list[str]:
    """The static confinement check (parse, imports, names) of one module, as one-line problems."""
    try:
        tree = ast.parse(code)
    except SyntaxError as e:
        return [f"SyntaxError: {e.msg} (line {e.lineno})"]
    return [str(f) for f in import_findings(tree) or name_findings(tree)]


def verify(package_dir: Path) -> list[str]:
    """Why the package at ``package_dir`` is not the package that was accepted (empty: it is)."""
    path = package_dir / MANIFEST
    try:
        listed = json.loads(path.read_text(encoding="utf-8"))["modules"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        return [f"no readable {MANIFEST} in {package_dir} ({type(e).__name__}); the package was not "
                "written by capmj.generate or was changed"]
    problems = []
    found = {p.relative_to(package_dir).as_posix(): p for p in sorted(package_dir.rglob("*.py"))}
    for rel in sorted(set(found) - set(listed)):
        problems.append(f"{rel} is not in the manifest (added after acceptance)")
    for rel, entry in sorted(listed.items()):
        if rel not in found:
            continue  # a listed module that is gone cannot run
        if sha256(found[rel]) != entry.get("sha256"):
            problems.append(f"{rel} was edited after acceptance (sha256 differs from the manifest)")
        problems += [f"{rel}: {p}" for p in static_problems(found[rel].read_text(encoding="utf-8"))]
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


def confinement_problems(entry: metadata.EntryPoint) -> list[str] | None:
    """``None`` for a package that is not generated; else what fails its confinement (``[]``: nothing)."""
    pkg = _package_dir(entry)
    if not (_generated(entry) or (pkg is not None and (pkg / MANIFEST).is_file())):
        return None
    if pkg is None:
        return [f"cannot locate the package of {entry.value!r} to check it"]
    return verify(pkg)


__all__ = ["GENERATED_TAG", "MANIFEST", "confinement_problems", "manifest_text", "sha256", "static_problems", "verify"]
