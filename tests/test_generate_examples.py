"""The generator's examples are the library's tasks written as a generated task must be (#27).

Each view must pass the generator's static checks *and* be the same task: run in a fresh module,
it draws the same scenes, gives the oracle the same goals and judges the same states as the
installed task.  So a small model that copies an example copies a task that works and imports
only the task API.
"""

from __future__ import annotations

import inspect
import sys
import types

import numpy as np
import pytest

from capmj.generate import GENERATED_TAG
from capmj.generate.examples import NotSelfContained, self_contained
from capmj.generate.library import load_library
from capmj.generate.static import static_checks
from capmj.sim.state import SceneState
from capmj.tasks import registry
from capmj.tasks.protocol import make_scene
from capmj_tasks.common import solved_state

LIBRARY = tuple(t.name for t in registry.list_tasks())


def _run(view: str, name: str) -> object:
    module = types.ModuleType(f"example_view_{name.replace('-', '_')}")
    sys.modules[module.__name__] = module  # dataclasses look their module up
    try:
        exec(compile(view, module.__name__, "exec"), module.__dict__)  # noqa: S102 - our own library's code
    finally:
        del sys.modules[module.__name__]
    return module.__dict__["TASK"]


def _same(a: object, b: object) -> None:
    """Equal, with arrays compared by value."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b))
    elif isinstance(a, (list, tuple)):
        assert isinstance(b, (list, tuple)) and len(a) == len(b)
        for x, y in zip(a, b):
            _same(x, y)
    elif isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys()
        for k in a:
            _same(a[k], b[k])
    else:
        assert a == b


@pytest.mark.parametrize("name", LIBRARY)
def test_each_view_is_the_same_task_importing_only_the_task_api(name: str) -> None:
    task = registry.get_task(name)
    source = inspect.getsource(sys.modules[type(task).__module__])
    try:
        view = self_contained(source)
    except NotSelfContained as e:
        assert "import" in str(e)  # the only reason in this library: a function-level import
        pytest.skip(f"{name} has no view: {e}")
    assert not [line for line in view.splitlines() if line.lstrip().startswith(("from capmj_tasks", "import capmj_tasks"))]
    assert [r.outcome for r in static_checks(view)] == ["pass", "pass", "pass"], static_checks(view)
    copy = _run(view, name)
    assert GENERATED_TAG in copy.tags  # type: ignore[attr-defined]
    for seed in (0, 1):
        mine, theirs = make_scene(copy, seed), make_scene(task, seed)  # type: ignore[arg-type]
        assert mine.goal == theirs.goal and mine.objects == theirs.objects
        _same(mine.info, theirs.info)
        goals = task.oracle_goals(theirs)
        _same([g.__dict__ for g in copy.oracle_goals(mine)], [g.__dict__ for g in goals])  # type: ignore[attr-defined]
        for state in (SceneState.from_specs(theirs.objects), solved_state(theirs, goals)):
            assert copy.evaluate(mine, state) == task.evaluate(theirs, state)  # type: ignore[attr-defined]


def test_most_of_the_library_can_be_shown() -> None:
    shown = [t.name for t in load_library() if t.example]
    assert len(shown) >= len(LIBRARY) - 2, sorted(set(LIBRARY) - set(shown))


def test_a_module_importing_only_the_api_is_shown_unchanged() -> None:
    src = "import math\n\nfrom capmj.tasks.protocol import Scene\n\nX = math.pi\n"
    assert self_contained(src) == src


def test_refusals_name_what_cannot_be_shown() -> None:
    with pytest.raises(NotSelfContained, match="os"):
        self_contained("import os\nTASK = os\n")
    with pytest.raises(NotSelfContained, match="another name"):
        self_contained("from capmj_tasks.common import shuffled as mix\n")
    with pytest.raises(NotSelfContained, match="would mean both"):  # the example defines a helper's name
        self_contained("from capmj_tasks.common import verdict\n\ndef Verdict():\n    pass\n")


def test_a_copied_helper_brings_what_it_uses() -> None:
    view = self_contained("from capmj_tasks.common import label\n\nX = label\n")
    assert "def label(" in view and "from capmj.tasks import predicates as P" in view
    assert "from capmj_tasks" not in view
