"""``capmj.agents.report.check_reads``: which model-written checks cannot tell one scene from another.

The records are those of a real settled scene (the matching-bowl task's solved state, seed 10001,
from the judge set); the checks are written as a small model writes them.
"""

from __future__ import annotations

import ast

import pytest

from capmj.agents.report.check_reads import MEASURED_KEYS, blind_problem, keys_read, unmatched_comparisons
from capmj.agents.report.scene_records import RECORD_KEYS, records
from capmj.judge.cases import Stage
from capmj.judge.judgeset import build_cases
from capmj.tasks.registry import get_task


@pytest.fixture(scope="module")
def rows() -> list[dict]:
    task = get_task("put-block-into-matching-bowl")
    oracle = build_cases(task, 10001, kinds=("oracle",))[0][0]
    return records(Stage(task, 10001).realise(oracle.poses()))


def test_the_measured_keys_are_the_record_keys_acting_can_change() -> None:
    assert set(MEASURED_KEYS) == set(RECORD_KEYS) - {"name", "kind", "color", "size"}
    assert keys_read(ast.parse('a = o["inside"]; b = o.get("level", 1); c = o["nope"]; d = o[k]')) == {"inside", "level"}


@pytest.mark.parametrize("check", [
    "judge = False\nreason = 'no'",
    "reds = [o for o in objects if o['color'] == 'red']\njudge = len(reds) == 2",
])
def test_a_check_that_reads_no_measured_key_is_blind(check: str, rows: list[dict]) -> None:
    assert "reads none of the measured keys" in str(blind_problem(check, [rows]))


def test_comparisons_with_values_no_record_can_have_are_found(rows: list[dict]) -> None:
    bowl = next(r for r in rows if r["kind"] == "bowl")
    block = next(r for r in rows if r["kind"] == "block")
    code = (f"a = [o for o in objects if o['inside'] != 'bowl']\n"          # a word, not a name
            f"b = [o for o in objects if 'top' == o['area']]\n"               # reversed operands
            f"c = [o for o in objects if o['area'] in ('left', 'top left')]\n"  # one of a tuple
            f"d = [o for o in objects if o['rests_on'] == {bowl['name']!r}]\n"  # a bowl can carry a block
            f"e = [o for o in objects if o['inside'] == {bowl['name']!r} and o['inside_color'] == {bowl['color']!r}]\n"
            f"f = [o for o in objects if 'bowl' in o['inside'] or {block['name']!r} in o['below']]\n"  # parts: fine
            f"g = [o for o in objects if o.get('color') == 'warm']\n")
    assert unmatched_comparisons(ast.parse(code), [rows]) == [("inside", "bowl"), ("area", "top"), ("area", "left"),
                                                             ("color", "warm")]
    problem = str(blind_problem(code, [rows]))
    assert problem.startswith("it compares \"inside\" with 'bowl'") and repr(bowl["name"]) in problem


def test_a_check_of_the_names_and_words_the_records_use_is_not_blind(rows: list[dict]) -> None:
    check = ("blocks = [o for o in objects if o['kind'] == 'block']\n"
             "wrong = [b['name'] for b in blocks if b['inside_color'] != b['color'] or b['rests_on'] == 'nothing']\n"
             "judge = not wrong")
    assert blind_problem(check, [rows]) is None
    assert blind_problem("judge = (", [rows]) is None  # a syntax error is the sandbox's to report
