"""The task protocol's scene method, ``sample_scene(rng)``, and the way from its old name ``generate``.

Why the rename (issue #28): "generate" also names the LLM task generator (``python -m
capmj.generate``), so "the generate check failed" or "generate ignores its rng" could mean either.
The method draws one scene from a seeded generator, and the protocol's other words are ``Scene``,
``Resample`` and ``make_scene``: ``sample_scene`` says what it does.

Why a deprecation path: third-party plugin packages implement the protocol and are released on
their own schedule.  The rules, in one place (the registry's validation, the task checker and
:func:`~capmj.tasks.protocol.make_scene` all ask this module):

* ``sample_scene`` only: the protocol.
* ``generate`` only: still loads and runs; the first scene drawn from a task of that class warns
  once (``DeprecationWarning``, pointing at the ``generate`` definition and naming the new method).
* both, bound to the same function (``generate = sample_scene``, what a package supporting old and
  new capmj writes): the protocol, no warning.
* both, different: refused.  capmj would call one and silently ignore the other (a subclass of a
  capmj task that still overrides ``generate`` would run its parent's scenes); no rule picking one
  is right, so the author must say which.

Only the standard library and :mod:`capmj.errors` are imported: the registry validates tasks
before anything heavy is loaded.
"""

from __future__ import annotations

import threading
import warnings
from typing import Any, Callable

from capmj.errors import TaskError

SCENE_METHOD = "sample_scene"
"""The task method that draws one scene from the episode's scene generator."""
DEPRECATED_SCENE_METHOD = "generate"
"""Its name before issue #28; accepted from task plugins with a ``DeprecationWarning``."""

_warned: set[type] = set()
"""Task classes already warned about in this process (one warning per class, not per scene)."""
_warned_lock = threading.Lock()


def uses_deprecated_name(task: Any) -> bool:
    """Whether ``task`` draws its scenes through the deprecated ``generate`` (it has no ``sample_scene``)."""
    return not hasattr(task, SCENE_METHOD) and callable(getattr(task, DEPRECATED_SCENE_METHOD, None))


def scene_method_problem(task: Any) -> str | None:
    """Why ``task`` has no usable scene method (``None`` when it has one, under either name)."""
    if uses_deprecated_name(task):
        return None
    new = getattr(task, SCENE_METHOD, None)
    if not callable(new):
        return f"'{SCENE_METHOD}' is missing or not callable"
    old = getattr(task, DEPRECATED_SCENE_METHOD, None)
    if old is not None and old != new:
        return (f"it defines both '{SCENE_METHOD}' and '{DEPRECATED_SCENE_METHOD}' (the old name of "
                f"'{SCENE_METHOD}') as different methods, and capmj would call only '{SCENE_METHOD}'; "
                f"delete '{DEPRECATED_SCENE_METHOD}', or alias it ({DEPRECATED_SCENE_METHOD} = {SCENE_METHOD}) "
                "to support older capmj")
    return None


def _warn_once(task: Any, legacy: Callable[..., Any]) -> None:
    cls = type(task)
    with _warned_lock:
        if cls in _warned:
            return
        _warned.add(cls)
    message = (f"{cls.__module__}.{cls.__qualname__} defines '{DEPRECATED_SCENE_METHOD}(rng)', the old name of "
               f"the task protocol's scene method; rename it to '{SCENE_METHOD}(rng)' "
               f"('{DEPRECATED_SCENE_METHOD}' will stop being called in a later capmj)")
    code = getattr(getattr(legacy, "__func__", legacy), "__code__", None)
    if code is None:
        warnings.warn(message, DeprecationWarning, stacklevel=4)
    else:  # point at the line to rename, in the plugin's own file
        warnings.warn_explicit(message, DeprecationWarning, code.co_filename, code.co_firstlineno)


def scene_sampler(task: Any) -> Callable[[Any], Any]:
    """The callable that draws ``task``'s scenes: ``task.sample_scene``, or for a task written
    before the rename its ``generate`` (warning once per task class).

    Raises :class:`~capmj.errors.TaskError` when :func:`scene_method_problem` finds a problem.
    """
    problem = scene_method_problem(task)
    if problem is not None:
        raise TaskError(f"task {getattr(task, 'name', task)!r} is not a valid task: {problem}")
    if uses_deprecated_name(task):
        legacy = getattr(task, DEPRECATED_SCENE_METHOD)
        _warn_once(task, legacy)
        return legacy
    return getattr(task, SCENE_METHOD)


__all__ = ["DEPRECATED_SCENE_METHOD", "SCENE_METHOD", "scene_method_problem", "scene_sampler", "uses_deprecated_name"]
