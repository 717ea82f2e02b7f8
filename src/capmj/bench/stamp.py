"""The version stamp of a task set: what two runs must share for their numbers to be comparable.

Per task, a SHA-256 over its code (the source of its module; for a generated task, the exact text
of the module its accepted package holds, :class:`~capmj.confine.proxy.ModuleSource`), the world's
MJCF templates (every ``mjcf/*.xml``) and capmj's version; beside them the hash of the prompt
folder the agent reads (``prompts``; None for an agent that reads none, the oracle); overall, a
SHA-256 over the tasks' stamps in name order and the prompts.  A benchmark fix to one task changes
that task's stamp and the overall one, never another task's.  ``report`` compares the stamps of the
tasks two runs share and their prompts where both read prompts (:func:`mismatches`), and refuses
runs that differ unless told otherwise: an oracle column stays comparable with an LLM one.

``config.json`` holds the stamp under ``stamp`` and every summary prints it (``summary.json``
``stamp``; the short form is the first :data:`SHORT` hex digits).
"""

from __future__ import annotations

import hashlib
import inspect
from importlib import metadata
from pathlib import Path
from typing import Any, Mapping, Sequence

SCHEMA = "capmj.task-stamp/1"
SHORT = 12
"""Hex digits of a stamp shown in text (the JSON holds all 64)."""


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def folder_hash(folder: Path | None, pattern: str = "*") -> str:
    """One SHA-256 over the relative names and contents of a folder's files (``__pycache__`` left out)."""
    h = hashlib.sha256()
    if folder is not None and folder.is_dir():
        for p in sorted(folder.rglob(pattern)):
            if p.is_file() and "__pycache__" not in p.parts:
                h.update(str(p.relative_to(folder)).encode() + b"\0" + hashlib.sha256(p.read_bytes()).digest())
    return h.hexdigest()


def task_code(task: Any) -> tuple[str, str]:
    """``(kind, sha256)`` of a task's code: ``generated`` (the accepted module text of a confined
    task), ``module`` (the source file of its class's module) or ``unknown`` (no source: the hash of
    its class's qualified name, so the stamp still names it)."""
    source = getattr(task, "source", None)
    text = getattr(source, "text", None)
    if isinstance(text, str):
        return "generated", _sha(text.encode())
    try:
        path = inspect.getsourcefile(type(task))
    except (TypeError, OSError):
        path = None
    if path and Path(path).is_file():
        return "module", _sha(Path(path).read_bytes())
    return "unknown", _sha(f"{type(task).__module__}.{type(task).__qualname__}".encode())


def capmj_version() -> str:
    try:
        return metadata.version("capmj")
    except metadata.PackageNotFoundError:
        import capmj

        return str(getattr(capmj, "__version__", "unknown"))


def task_set_stamp(tasks: Mapping[str, Any], prompts: Path | None) -> dict[str, Any]:
    """The stamp of ``tasks`` (name -> task object) as run with the prompt folder ``prompts``
    (None: the agent reads no prompt)."""
    from capmj.resources import packaged

    mjcf = folder_hash(packaged("mjcf"), "*.xml")
    prompt = folder_hash(prompts) if prompts is not None else None
    version = capmj_version()
    per: dict[str, dict[str, str]] = {}
    for name in sorted(tasks):
        kind, code = task_code(tasks[name])
        stamp = _sha("\n".join((name, code, mjcf, version)).encode())
        per[name] = {"stamp": stamp, "code": code, "kind": kind}
    return {"schema": SCHEMA, "overall": overall(per, prompt), "capmj": version, "mjcf": mjcf, "prompts": prompt,
            "tasks": per}


def overall(per_task: Mapping[str, Mapping[str, str]], prompts: str | None = None) -> str:
    """The overall stamp of per-task stamps (name order) and the prompts' hash."""
    lines = [f"{n}:{per_task[n]['stamp']}" for n in sorted(per_task)] + [f"prompts:{prompts or 'none'}"]
    return _sha("\n".join(lines).encode())


def short(stamp: str | None) -> str:
    return (stamp or "none")[:SHORT]


def mismatches(stamps: Mapping[str, Mapping[str, Any] | None], tasks: Sequence[str]) -> list[str]:
    """One sentence per compared task whose stamp differs between runs (by source name), and one
    per run without a stamp (a run from before stamps); empty when all match."""
    out = [f"{src}: no task stamp (a run from before stamps were recorded)" for src, s in stamps.items() if not s]
    have = {src: s for src, s in stamps.items() if s}
    if len(have) < 2:
        return out
    for task in tasks:
        values = {src: (s.get("tasks") or {}).get(task, {}).get("stamp") for src, s in have.items()}
        values = {src: v for src, v in values.items() if v is not None}
        if len(set(values.values())) > 1:
            what = _what_differs(task, {src: have[src] for src in values})
            out.append(f"task {task}: stamps differ ({', '.join(f'{src}={short(v)}' for src, v in values.items())})"
                       + (f"; {what}" if what else ""))
    prompts = {src: s.get("prompts") for src, s in have.items() if s.get("prompts")}
    if len(set(prompts.values())) > 1:
        out.append(f"prompt folder stamps differ ({', '.join(f'{src}={short(v)}' for src, v in prompts.items())}); "
                   "the prompts the agents read changed")
    return out


def _what_differs(task: str, stamps: Mapping[str, Mapping[str, Any]]) -> str:
    parts = []
    for part, value in (("code", lambda s: (s.get("tasks") or {}).get(task, {}).get("code")),
                        ("MJCF templates", lambda s: s.get("mjcf")), ("capmj version", lambda s: s.get("capmj"))):
        if len({value(s) for s in stamps.values()}) > 1:
            parts.append(part)
    return "differing: " + ", ".join(parts) if parts else ""


__all__ = ["SCHEMA", "SHORT", "capmj_version", "folder_hash", "mismatches", "overall", "short", "task_code",
           "task_set_stamp"]
