"""The scene method's rename (issue #28): ``sample_scene``, and tasks still written with ``generate``.

The tasks here delegate to a built-in task, so "still runs" is checked against real scenes: the
old-style task must get the very scene of each seed that the built-in one gets.  Each test makes
its own classes, because the deprecation warning is once per task class and per process.  The
installed-plugin path is in ``tests/test_registry.py``; the checker's and the generator's rules
in ``tests/test_taskcheck.py`` and ``tests/test_generate.py``.
"""

from __future__ import annotations

import warnings

import pytest

from capmj.errors import PluginError, TaskError
from capmj.tasks.protocol import make_scene
from capmj.tasks.registry import TaskRegistry, get_task, validate_task
from capmj.tasks.scene_method import scene_method_problem, uses_deprecated_name

BASE = get_task("stack-all-blocks-on-a-zone")
DOC = """Stack the blocks (a test wrapper of stack-all-blocks-on-a-zone).

    Task Description: as the base task.
    Randomizations: as the base task.
    Success Conditions: as the base task.
    """


def legacy_class(name: str = "legacy-stack") -> type:
    """A new task class written before the rename: it defines only ``generate``."""

    class Legacy:
        __doc__ = DOC
        tags = frozenset({"test"})

        def __init__(self) -> None:
            self.name = name

        def generate(self, rng):  # noqa: ANN001, ANN201
            return BASE.sample_scene(rng)

        def oracle_goals(self, scene):  # noqa: ANN001, ANN201
            return BASE.oracle_goals(scene)

        def evaluate(self, scene, state):  # noqa: ANN001, ANN201
            return BASE.evaluate(scene, state)

    return Legacy


def deprecations(record: list[warnings.WarningMessage]) -> list[warnings.WarningMessage]:
    return [w for w in record if issubclass(w.category, DeprecationWarning)]


def test_a_task_with_only_generate_gets_the_same_scenes_and_warns_once_per_class():
    cls = legacy_class()
    a, b = cls(), cls()
    assert uses_deprecated_name(a) and validate_task(a, "legacy-stack") == []
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        scenes = [make_scene(a, 10001), make_scene(a, 10003), make_scene(b, 10001)]
        first = deprecations(got)
        make_scene(legacy_class()(), 10001)  # another class: its own warning
        second = deprecations(got)[len(first):]
    assert scenes == [make_scene(BASE, 10001), make_scene(BASE, 10003), make_scene(BASE, 10001)]
    assert len(first) == 1 and len(second) == 1
    message = str(first[0].message)
    assert "Legacy" in message and "'generate(rng)'" in message and "rename it to 'sample_scene(rng)'" in message
    assert first[0].filename == __file__  # it points at the plugin's own `def generate`


def test_a_registry_loads_an_old_style_task():
    reg = TaskRegistry()
    task = reg.register(legacy_class("legacy-registered")())
    assert reg.get_task("legacy-registered") is task
    with pytest.warns(DeprecationWarning, match="sample_scene"):
        assert make_scene(task, 10005) == make_scene(BASE, 10005)


def test_an_alias_for_older_capmj_is_the_protocol_without_a_warning():
    cls = legacy_class()
    cls.sample_scene = cls.generate  # what a plugin supporting old and new capmj writes
    task = cls()
    assert not uses_deprecated_name(task) and scene_method_problem(task) is None
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        assert make_scene(task, 10001) == make_scene(BASE, 10001)


def test_both_names_as_different_methods_are_refused():
    cls = legacy_class()
    cls.sample_scene = lambda self, rng: BASE.sample_scene(rng)
    task = cls()
    problem = scene_method_problem(task)
    assert problem is not None and "both 'sample_scene' and 'generate'" in problem
    assert problem in validate_task(task)
    with pytest.raises(PluginError, match="both 'sample_scene' and 'generate'") as e:
        TaskRegistry().register(task)
    assert isinstance(e.value, TaskError)
    with pytest.raises(TaskError, match="delete 'generate', or alias it"):
        make_scene(task, 10001)


def test_a_subclass_of_a_builtin_task_still_overriding_generate_is_refused():
    """The case the refusal exists for: preferring sample_scene would silently run the parent's scenes."""

    class Narrower(type(BASE)):  # type: ignore[misc]
        def generate(self, rng):  # noqa: ANN001, ANN201
            raise AssertionError("never called")

    with pytest.raises(PluginError, match="both 'sample_scene' and 'generate'"):
        TaskRegistry().register(Narrower())


def test_a_task_with_neither_name_is_invalid():
    cls = legacy_class()
    del cls.generate
    task = cls()
    assert scene_method_problem(task) == "'sample_scene' is missing or not callable"
    assert "'sample_scene' is missing or not callable" in validate_task(task)
    with pytest.raises(TaskError, match="'sample_scene' is missing"):
        make_scene(task, 10001)
