"""The generator's view of the installed task library, read from the registry at run time.

Why dynamic: the best examples for a new task are whatever tasks are installed (the built-in
A–J, the generated-task issue's ten, third-party plugins), so nothing here names a task.  Only
the registry's public functions are used; a plugin that fails to load is left out, never fatal.
The task API reference shown to the LLM is built from the live signatures and docstrings of
``capmj.tasks`` and ``capmj.sim`` (one fact, one place: the prompt cannot drift from the code).
"""

from __future__ import annotations

import importlib
import inspect
import sys
from dataclasses import dataclass
from types import ModuleType

from capmj.confine.allowlist import CAPMJ_API, ordered_members
from capmj.confine.proxy import ConfinedTask
from capmj.errors import CapmjError
from capmj.generate.examples import NotSelfContained, self_contained
from capmj.tasks import registry
from capmj.tasks.protocol import make_scene

MAX_SOURCE_CHARS = 12_000
"""An example is cut beyond this (a prompt budget, not a correctness limit)."""


@dataclass(frozen=True)
class LibraryTask:
    """One installed task: its name, a sample goal (seed 0), its docstring summary, and its module
    as the writing turn shows it (:func:`~capmj.generate.examples.self_contained`; ``""`` when
    it cannot be shown importing only the task API)."""

    name: str
    goal: str
    summary: str
    example: str


def load_library() -> tuple[LibraryTask, ...]:
    """Every loadable installed task, sorted by name."""
    out = []
    for info in registry.list_tasks():
        try:
            task = registry.get_task(info.name)
            # an LLM-written task: its goal as recorded at acceptance (listing starts no jailed process)
            goal = task.sample_goal or "" if isinstance(task, ConfinedTask) else make_scene(task, 0).goal
        except (CapmjError, Exception):  # noqa: BLE001 - a broken plugin is not an example
            continue
        doc = inspect.getdoc(task) or ""
        summary = doc.strip().splitlines()[0] if doc.strip() else ""
        module = sys.modules.get(type(task).__module__)
        try:
            if isinstance(task, ConfinedTask):  # its verified text, read as text
                example = self_contained(task.source.text)
            else:
                example = self_contained(inspect.getsource(module)) if module is not None else ""
        except (OSError, TypeError, SyntaxError, NotSelfContained):  # shown only if it can be shown right
            example = ""
        out.append(LibraryTask(info.name, goal, summary, example[:MAX_SOURCE_CHARS]))
    return tuple(out)


def similar(name: str, goal: str, library: tuple[LibraryTask, ...], k: int = 3) -> list[str]:
    """The ``k`` names of library tasks with an example sharing most words with the proposal (a
    deterministic fallback when the LLM's picks are unusable)."""
    words = set(name.split("-")) | set(goal.lower().replace(".", " ").split())
    scored = sorted((t for t in library if t.example), key=lambda t: (-len(words & (set(t.name.split("-")) | set(t.goal.lower().split()))), t.name))
    return [t.name for t in scored[:k]]


LONG_DEFAULT = 24
"""A default whose repr is longer than this is shown by the name of the module constant equal to
it (``SPAWN_BOUNDS``, ``DEFAULT_COLORS``) or as ``...``: the reference is read by small models at
~20-50 tokens/s, and a repeated 80-character tuple teaches nothing."""


def _literal(v: object) -> str:
    """``repr`` with floats to 4 significant digits and sets in sorted order: a set's repr follows
    the hash seed, and the prompt must be the same text in every process (its LLM cache key and a
    server's prefix cache depend on it)."""
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, (set, frozenset)):
        items = ", ".join(sorted(repr(x) for x in v))
        return f"{type(v).__name__}({{{items}}})" if v else f"{type(v).__name__}()"
    return repr(v)


def _value(v: object, module: ModuleType) -> str:
    """A short text for a default or a constant: floats to 4 significant digits, long values by
    the name of an equal public constant of ``module``."""
    text = _literal(v)
    if isinstance(v, float) or len(text) <= LONG_DEFAULT:
        return text
    for name, const in vars(module).items():
        if name.isupper() and type(const) is type(v):
            try:
                if const == v:
                    return name
            except Exception:  # noqa: BLE001,S112 - an odd __eq__ only loses the short name
                continue
    return "..."


def _signature(obj: object, module: ModuleType) -> str:
    """``(a: T, b: U = d) -> R`` without the quotes of postponed annotations, long defaults named
    (:func:`_value`) and no ``-> None`` on classes."""
    try:
        sig = inspect.signature(obj)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return ""
    parts, star = [], False
    for p in sig.parameters.values():
        if p.kind is p.KEYWORD_ONLY and not star:
            parts.append("*")
            star = True
        prefix = "*" if p.kind is p.VAR_POSITIONAL else "**" if p.kind is p.VAR_KEYWORD else ""
        star = star or p.kind is p.VAR_POSITIONAL
        text = prefix + p.name
        if p.annotation is not p.empty:
            text += f": {str(p.annotation).strip(chr(39))}"
        if p.default is not p.empty:
            text += f" = {_value(p.default, module)}"
        parts.append(text)
    out = f"({', '.join(parts)})"
    ret = sig.return_annotation
    if ret is not sig.empty and not inspect.isclass(obj) and str(ret).strip("'") != "None":
        out += f" -> {str(ret).strip(chr(39))}"
    return out


def _members(module: ModuleType, names: tuple[str, ...]) -> list[str]:
    lines = [f"# {module.__name__}"]
    for n in names:
        obj = getattr(module, n)
        doc = (inspect.getdoc(obj) or "").strip().split("\n\n")[0].replace("\n", " ").replace("``", "`")
        if inspect.isclass(obj) or inspect.isfunction(obj):
            sig = _signature(obj, module)
            lines.append(f"{n}{sig}: {doc}" if doc else f"{n}{sig}")
        else:
            lines.append(f"{n} = {_literal(obj)}")
    return lines


_NOTES = {
    "capmj.tasks.spawn": "Spawner methods: block(color, size='small', region=None, avoid=(), yaw=None), zone(color, "
                         "scale=1.0, ...), bowl(color, ...); .objects is the tuple of placed ObjectSpec (ids 1, 2, ... in "
                         "creation order).",
    "capmj.sim.state": "SceneState methods: spec(obj_id) -> ObjectSpec, pos(obj_id) -> np.ndarray, of_kind(kind), "
                       "poses[obj_id].yaw / .tilt; SceneState.from_specs(objects) is the spawn state.",
    "capmj.sim.objects": "ObjectSpec attributes: obj_id, kind, color, pos (centre), yaw, size (blocks), scale (zones), "
                         "height, footprint_radius, fixed.",
}
"""What a signature cannot show: the methods and attributes of the main objects."""


def api_reference() -> str:
    """Signatures and first docstring paragraphs of capmj's task API: exactly the names the
    static check allows (:data:`capmj.confine.allowlist.CAPMJ_API`), in that order."""
    lines = []
    for name in CAPMJ_API:
        lines += _members(importlib.import_module(name), ordered_members(name))
        if name in _NOTES:
            lines.append(_NOTES[name])
    return "\n".join(lines)


__all__ = ["LibraryTask", "api_reference", "load_library", "similar"]
