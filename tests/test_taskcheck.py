"""The public task checker (capmj.taskcheck, ``python -m capmj.tasks check``).

Broken tasks are the hand-written generator candidates (tests/generator_candidates/), imported
in this process: they are our own fixtures, not LLM output.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from capmj.sim.objects import ObjectSpec
from capmj.taskcheck import CHECKS, CheckConfig, check_task, goal_text_problems
from capmj.tasks.protocol import Scene
from generator_script import CANDIDATES
from module_loader import load_module


def load(file: str):
    return load_module(CANDIDATES / file, f"cand_{file[:-3]}").TASK


def test_goal_text_names_only_what_exists():
    objs = (ObjectSpec(1, "zone", "red", (0.5, 0.0, 0.0005)), ObjectSpec(2, "block", "blue", (0.4, 0.1, 0.02), size="small"))
    assert goal_text_problems(Scene(objs, "Put the blue block in the red zone.")) == []
    assert any("'green'" in p for p in goal_text_problems(Scene(objs, "Put the green block in the red zone.")))
    assert any("red block" in p for p in goal_text_problems(Scene(objs, "Put the red block in the blue zone.")))
    assert any("bowl" in p for p in goal_text_problems(Scene(objs, "Put the blue block in the bowl.")))
    assert any("big" in p for p in goal_text_problems(Scene(objs, "Put the bigger block in the red zone.")))
    assert any("warm" in p for p in goal_text_problems(Scene(objs, "Stack the warm blocks.")))


@pytest.mark.parametrize("file, failing, words", [
    ("broken_no_docstring_parts.py", "protocol", "Task Description:"),
    ("broken_ignores_rng.py", "scenes", "same scene"),
    ("broken_absent_colour.py", "goal_text", "no object is"),
    ("broken_solved_at_reset.py", "not_solved_at_reset", "already a success"),
])
def test_broken_task_fails_its_check_and_later_checks_are_skipped(file, failing, words):
    report = check_task(load(file), CheckConfig.first(2))
    assert not report.passed and report.first_failure.name == failing
    assert words in report.first_failure.detail
    k = CHECKS.index(failing)
    assert all(r.passed for r in report.results[:k])
    assert all(r.outcome == "skip" for r in report.results[k + 1:])
    assert f"NOT OK: {failing}" in report.text()


def test_required_name_and_tags_are_protocol():
    report = check_task(load("good_zone_color.py"), CheckConfig.first(1, name="other", required_tags=frozenset({"x"})),
                        checks=("protocol",))
    assert "entry point is called 'other'" in report.results[0].detail and "'x'" in report.results[0].detail


def test_the_old_scene_method_name_passes_for_plugins_and_fails_where_refused(tmp_path):
    """An installed plugin still named ``generate`` passes (with a note naming the new method);
    with ``allow_deprecated=False`` (the generator's worker) the protocol check fails saying so."""
    code = (CANDIDATES / "good_zone_color.py").read_text().replace("def sample_scene(", "def generate(")
    path = tmp_path / "old_name.py"
    path.write_text(code)
    module = load_module(path, "cand_old_name")
    with pytest.warns(DeprecationWarning, match="sample_scene"):
        allowed = check_task(module.TASK, CheckConfig.first(2), checks=("protocol", "scenes"))
    assert allowed.passed and "deprecated: 'generate' is the old name of 'sample_scene'" in allowed.results[0].detail
    refused = check_task(module.TASK, CheckConfig.first(2, allow_deprecated=False), checks=("protocol", "scenes"))
    assert [r.outcome for r in refused.results] == ["fail", "skip"]
    assert "defines 'generate(self, rng)' but no 'sample_scene(self, rng)'" in refused.results[0].detail


def test_cli_checks_an_installed_task_with_physics():
    r = subprocess.run([sys.executable, "-m", "capmj.tasks", "check", "stack-all-blocks-on-a-zone", "--seeds", "1",
                        "--json"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    assert report["passed"] and [c["name"] for c in report["checks"]] == list(CHECKS)
    assert report["checks"][CHECKS.index("oracle_solves")]["data"]["rate"] == 1.0


def test_cli_unknown_task_is_exit_2():
    r = subprocess.run([sys.executable, "-m", "capmj.tasks", "check", "no-such-task"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and "unknown task or tag 'no-such-task'" in r.stderr


def test_every_check_has_its_runner_in_the_published_order() -> None:
    from capmj.taskcheck import checks

    assert tuple(checks._RUNNERS) == CHECKS
