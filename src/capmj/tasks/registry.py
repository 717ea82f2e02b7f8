"""The task registry over the ``capmj.tasks`` entry-point group; each entry names a task object
or a zero-argument factory (class or function) returning one.

Why it works this way:

* Entry points, not a table: third-party packages add tasks from their own ``pyproject.toml``,
  and the built-in tasks A–J take the same path, so every benchmark run exercises it.
* :func:`list_tasks` reads metadata only, so a broken or heavy plugin cannot break ``--list``.
* :func:`get_task` imports one plugin, validates and caches it; any failure becomes a cached
  :class:`PluginError` naming the distribution, its version and ``ErrorClass: message``, and no
  other task notices it.  A name declared by two distributions is unusable (picking one would
  make results depend on install order); the error names both.
* A docstring lacking a ``Task Description:``, ``Randomizations:`` or ``Success Conditions:``
  heading is an *error*, not a warning: it is the task's specification, the one place saying
  what success means; a warning scrolls by unseen in a run of hundreds of episodes, and the fix
  is three headings.
* A package written by the task generator (it ships a confinement manifest, or its distribution
  has the keyword ``generated-by-llm``) is never imported: it is re-checked (every file unchanged
  since acceptance, every module passing the static confinement check, else a
  :class:`~capmj.errors.ConfinementError` and nothing of it runs) and then answered by a jailed
  process (:func:`capmj.confine.manifest.confined_task`); its name, tags and docstring come from
  the manifest, so listing and tag selection start no process.
* A task written before ``generate`` became ``sample_scene`` still loads (it warns when it first
  samples a scene); one defining both as different methods is a :class:`PluginError`
  (:mod:`capmj.tasks.scene_method` says why).
* ``CAPMJ_DISABLE_PLUGINS=1`` turns discovery off (hermetic tests, notebooks); then only tasks
  added with :func:`register` exist.
"""

from __future__ import annotations

import difflib
import importlib
import inspect
import os
import re
import threading
import warnings
from collections.abc import Set as AbstractSet
from dataclasses import dataclass, field
from importlib import metadata
from typing import TYPE_CHECKING, Any, Sequence

from capmj.confine.manifest import confined_task, confinement_problems, is_generated
from capmj.errors import ConfigError, ConfinementError, PluginError, UnverifiedPackage
from capmj.tasks.builtin import RENAMED_TAGS
from capmj.tasks.scene_method import SCENE_METHOD, scene_method_problem, uses_deprecated_name

if TYPE_CHECKING:  # the protocol pulls in numpy and the simulator; listing must stay cheap
    from capmj.tasks.protocol import Task

GROUP = "capmj.tasks"
DISABLE_ENV = "CAPMJ_DISABLE_PLUGINS"
DOC_PARTS = ("Task Description", "Randomizations", "Success Conditions")
REGISTERED = "<registered>"
"""The ``distribution`` of tasks added with :func:`register`."""
_METHODS = ("oracle_goals", "evaluate")
"""The protocol's methods besides ``sample_scene``, whose rules (it has a deprecated old name) are
in :mod:`capmj.tasks.scene_method`."""


@dataclass(frozen=True)
class TaskInfo:
    """A task as known before importing it: its name, who provides it, and the entry-point value."""

    name: str
    distribution: str
    version: str
    value: str

    def __str__(self) -> str:
        return f"{self.name}  [{f'{self.distribution} {self.version}'.strip()}]  {self.value}"


@dataclass
class _Scan:
    entries: dict[str, TaskInfo] = field(default_factory=dict)
    points: dict[str, metadata.EntryPoint] = field(default_factory=dict)
    clashes: dict[str, PluginError] = field(default_factory=dict)


def plugins_disabled() -> bool:
    """Whether ``CAPMJ_DISABLE_PLUGINS`` is set to a true value (read on every call)."""
    return os.environ.get(DISABLE_ENV, "").strip().lower() in {"1", "true", "yes", "on"}


def _info(ep: metadata.EntryPoint) -> TaskInfo:
    dist = getattr(ep, "dist", None)
    name = (dist.metadata["Name"] or "<unknown>") if dist is not None else "<unknown>"
    return TaskInfo(ep.name, name, dist.version if dist is not None else "?", ep.value)


def validate_task(task: Any, name: str | None = None) -> list[str]:
    """Why ``task`` does not follow the task protocol (empty when it does).

    ``name``, when given, is the entry-point name the task's own ``name`` must equal.
    """
    problems: list[str] = []
    tname = getattr(task, "name", None)
    if not isinstance(tname, str) or not tname:
        problems.append(f"'name' must be a non-empty str, got {tname!r}")
    elif name is not None and tname != name:
        problems.append(f"its name is {tname!r} but its entry point is called {name!r}")
    tags = getattr(task, "tags", None)
    if not isinstance(tags, AbstractSet) or not all(isinstance(t, str) for t in tags):
        problems.append(f"'tags' must be a (frozen)set of str, got {tags!r}")
    scene = scene_method_problem(task)
    if scene is not None:
        problems.append(scene)
    for m in _METHODS:
        if not callable(getattr(task, m, None)):
            problems.append(f"'{m}' is missing or not callable")
    doc = inspect.getdoc(task) or ""
    missing = [p for p in DOC_PARTS if not re.search(rf"^\s*{p}\s*:", doc, re.MULTILINE)]
    if missing:
        problems.append(f"its docstring lacks the heading(s) {', '.join(p + ':' for p in missing)}")
    return problems


def _instantiate(obj: Any) -> Any:
    """An entry's target: a class or a zero-argument function is called, a task object kept."""
    if inspect.isclass(obj):
        return obj()
    has_methods = all(hasattr(obj, m) for m in _METHODS) and (hasattr(obj, SCENE_METHOD) or uses_deprecated_name(obj))
    if not has_methods and callable(obj):
        return obj()
    return obj


def _tokens(selector: str | Sequence[str]) -> list[str]:
    parts = [selector] if isinstance(selector, str) else list(selector)
    return [t.strip() for p in parts for t in str(p).split(",") if t.strip()]


class TaskRegistry:
    """Tasks by name: the entry points of :data:`GROUP` (scanned once, loaded one by one on
    demand) plus tasks added with :meth:`register`.  Thread-safe.

    The module functions (:func:`get_task`, :func:`resolve`…) act on :data:`DEFAULT`; a separate
    instance gives a test or a tool its own view without touching the process-wide one.
    """

    def __init__(self, group: str = GROUP) -> None:
        self.group = group
        self._lock = threading.RLock()
        self._scan_cache: _Scan | None = None
        self._registered: dict[str, tuple[TaskInfo, Task]] = {}
        self._loaded: dict[str, Task] = {}
        self._failed: dict[str, PluginError] = {}

    def _scan(self) -> _Scan:
        """The entry points of the group, read once (metadata only); empty when plugins are off."""
        if plugins_disabled():
            return _Scan()
        with self._lock:
            if self._scan_cache is None:
                by_name: dict[str, list[metadata.EntryPoint]] = {}
                for ep in metadata.entry_points(group=self.group):
                    by_name.setdefault(ep.name, []).append(ep)
                scan = _Scan()
                for name, eps in sorted(by_name.items()):
                    if len(eps) == 1:
                        scan.entries[name], scan.points[name] = _info(eps[0]), eps[0]
                        continue
                    who = ", ".join(f"{i.distribution} {i.version} ({i.value})" for i in map(_info, eps))
                    scan.clashes[name] = PluginError(
                        f"task name {name!r} is declared by more than one distribution: {who}; "
                        "it is unusable until all but one are uninstalled")
                self._scan_cache = scan
            return self._scan_cache

    def list_tasks(self) -> list[TaskInfo]:
        """Every usable task name, sorted, with its provider; imports no plugin.

        Names declared by two distributions are left out (they are in :meth:`broken`).
        """
        with self._lock:
            found = dict(self._scan().entries)
            found.update({n: info for n, (info, _) in self._registered.items()})
            return [found[n] for n in sorted(found)]

    def _unknown(self, name: str) -> ConfigError:
        valid = [i.name for i in self.list_tasks()]
        close = difflib.get_close_matches(name, valid, n=3, cutoff=0.75)
        hint = f"; did you mean {', '.join(map(repr, close))}?" if close else ""
        off = f" (entry-point plugins are disabled by {DISABLE_ENV})" if plugins_disabled() else ""
        return ConfigError(f"unknown task {name!r}{hint}; valid tasks{off}: {', '.join(valid) or 'none'}")

    def get_task(self, name: str) -> Task:
        """The task called ``name``: imports only its plugin, validates and caches it.

        Raises :class:`ConfigError` for an unknown name and :class:`PluginError` when the plugin
        fails to import or validate or its name is declared twice.
        """
        with self._lock:
            if name in self._registered:
                return self._registered[name][1]
            scan = self._scan()
            if name in scan.clashes:
                raise scan.clashes[name]
            if name not in scan.entries:
                raise self._unknown(name)
            if name in self._loaded:
                return self._loaded[name]
            if name in self._failed:
                raise self._failed[name]
            info = scan.entries[name]
            where = f"task plugin {name!r} from {info.distribution} {info.version} ({info.value})"
            point = scan.points[name]
            try:
                if is_generated(point):  # LLM-written: never imported here, answered by a jailed process
                    task: Task = confined_task(point)
                else:
                    task = _instantiate(point.load())
            except UnverifiedPackage as e:  # changed since acceptance: it never runs, not even jailed
                self._failed[name] = ConfinementError(
                    f"{where} is LLM-written and fails its confinement check, so it is not imported: {e}")
                raise self._failed[name] from None
            except Exception as e:  # anything a foreign module raises at import must stay contained
                self._failed[name] = PluginError(f"{where} failed to load: {type(e).__name__}: {e}")
                raise self._failed[name] from e
            problems = validate_task(task, name)
            if problems:
                self._failed[name] = PluginError(f"{where} is not a valid task: {'; '.join(problems)}")
                raise self._failed[name]
            self._loaded[name] = task
            return task

    def confinement(self, name: str) -> list[str] | None:
        """What fails the confinement check of ``name``'s package (``[]``: nothing), or ``None``
        when the task is not LLM-written; imports nothing."""
        with self._lock:
            point = self._scan().points.get(name)
        return None if point is None else confinement_problems(point)

    def register(self, task: Task, *, replace: bool = False) -> Task:
        """Add a task by hand (tests, notebooks); works with plugins disabled.  Returns ``task``.

        The task is validated like a plugin.  A name that already exists raises
        :class:`PluginError` unless ``replace`` is true, in which case this task shadows the other.
        """
        problems = validate_task(task)
        if problems:
            raise PluginError(f"cannot register {getattr(task, 'name', task)!r}: {'; '.join(problems)}")
        with self._lock:
            scan = self._scan()
            taken = task.name in self._registered or task.name in scan.entries or task.name in scan.clashes
            if not replace and taken:
                raise PluginError(f"a task named {task.name!r} already exists; pass replace=True to shadow it")
            value = f"{type(task).__module__}:{type(task).__qualname__}"
            self._registered[task.name] = (TaskInfo(task.name, REGISTERED, "", value), task)
        return task

    def tags_of(self, name: str) -> frozenset[str]:
        """The tags of task ``name`` (imports its plugin)."""
        return frozenset(self.get_task(name).tags)

    def broken(self, load: bool = False) -> dict[str, PluginError]:
        """Tasks known to be unusable, by name: clashing names, and plugins that failed to load.

        Only plugins someone tried to load are known to fail; ``load=True`` tries them all first.
        """
        with self._lock:
            if load:
                for info in self.list_tasks():
                    try:
                        self.get_task(info.name)
                    except PluginError:
                        pass
            scan = self._scan()
            out = {n: e for n, e in scan.clashes.items() if n not in self._registered}
            out.update({n: e for n, e in self._failed.items() if n in scan.entries and n not in self._registered})
            return dict(sorted(out.items()))

    def resolve(self, selector: str | Sequence[str]) -> list[str]:
        """Expand task names, tags and ``all`` (comma-separated and/or a list) to task names.

        The result keeps the selector's order, drops repeats, and sorts the names within one
        ``all`` or tag.  A name counts before a tag of the same spelling.  Names and ``all`` need
        metadata only (a plugin that fails to import then fails at :meth:`get_task`, per
        episode).  A renamed tag (:data:`~capmj.tasks.builtin.RENAMED_TAGS`) still selects what
        carries its new name, with a ``FutureWarning``, besides any plugin's own use of the old one.  Tags need the task objects, so resolving a tag imports the plugins; those that
        fail are skipped and listed by :meth:`broken` instead of failing the whole selection.
        Unknown entries raise :class:`ConfigError` naming the valid names and tags.
        """
        tokens = _tokens(selector)
        if not tokens:
            raise ConfigError("empty task selection; give task names, tags or 'all'")
        names = [i.name for i in self.list_tasks()]
        known = set(names) | set(self._scan().clashes)
        index: dict[str, frozenset[str]] = {}

        def tag_index() -> dict[str, frozenset[str]]:
            """Tags of every loadable task, built on first need (imports the plugins)."""
            if not index:
                for n in names:
                    try:
                        index[n] = self.tags_of(n)
                    except PluginError:
                        pass  # recorded in broken()
            return index

        out: list[str] = []
        unknown: list[str] = []
        for tok in tokens:
            if tok == "all":
                picked = names
            elif tok in known:
                picked = [tok]
            else:
                picked = [n for n, tags in tag_index().items() if tok in tags]
                renamed = [n for n, tags in tag_index().items() if RENAMED_TAGS.get(tok) in tags]
                if renamed:
                    warnings.warn(f"tag {tok!r} is now {RENAMED_TAGS[tok]!r} (it marked capmj's hand-written tasks "
                                  f"1-10, not LLM output); select {RENAMED_TAGS[tok]!r}", FutureWarning, stacklevel=2)
                    picked = sorted({*picked, *renamed})
                if not picked:
                    unknown.append(tok)
            out.extend(n for n in picked if n not in out)
        if unknown:
            tags = sorted({t for ts in tag_index().values() for t in ts})
            close = difflib.get_close_matches(unknown[0], names + tags, n=3, cutoff=0.6)
            hint = f"; did you mean {', '.join(map(repr, close))}?" if close else ""
            bad = self.broken()
            failed = f"; unusable plugins: {', '.join(bad)}" if bad else ""
            raise ConfigError(f"unknown task or tag {', '.join(map(repr, unknown))}{hint}; valid tasks: "
                              f"{', '.join(names) or 'none'}; valid tags: {', '.join(tags) or 'none'}; "
                              f"or 'all'{failed}")
        return out

    def reset(self) -> None:
        """Forget discovered entry points, loaded and registered tasks (e.g. after installing a
        package in a running process)."""
        with self._lock:
            self._scan_cache = None
            self._registered.clear()
            self._loaded.clear()
            self._failed.clear()
        importlib.invalidate_caches()


DEFAULT = TaskRegistry()
"""The process-wide registry the module functions below use."""


def list_tasks() -> list[TaskInfo]:
    """:meth:`TaskRegistry.list_tasks` of :data:`DEFAULT`."""
    return DEFAULT.list_tasks()


def get_task(name: str) -> Task:
    """:meth:`TaskRegistry.get_task` of :data:`DEFAULT`."""
    return DEFAULT.get_task(name)


def register(task: Task, *, replace: bool = False) -> Task:
    """:meth:`TaskRegistry.register` on :data:`DEFAULT`."""
    return DEFAULT.register(task, replace=replace)


def tags_of(name: str) -> frozenset[str]:
    """:meth:`TaskRegistry.tags_of` of :data:`DEFAULT`."""
    return DEFAULT.tags_of(name)


def broken(load: bool = False) -> dict[str, PluginError]:
    """:meth:`TaskRegistry.broken` of :data:`DEFAULT`."""
    return DEFAULT.broken(load)


def resolve(selector: str | Sequence[str]) -> list[str]:
    """:meth:`TaskRegistry.resolve` on :data:`DEFAULT`."""
    return DEFAULT.resolve(selector)


def confinement(name: str) -> list[str] | None:
    return DEFAULT.confinement(name)


def reset() -> None:
    """:meth:`TaskRegistry.reset` of :data:`DEFAULT`."""
    DEFAULT.reset()


__all__ = [
    "DEFAULT", "DISABLE_ENV", "DOC_PARTS", "GROUP", "REGISTERED", "TaskInfo", "TaskRegistry", "broken", "confinement",
    "get_task", "list_tasks",
    "plugins_disabled", "register", "reset", "resolve", "tags_of", "validate_task",
]
