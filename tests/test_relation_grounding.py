"""Literals a relation check takes from nowhere (capmj.agents.report.relations.picks): each rule fires on
the misreading it is for, and stays quiet on the readings a person would write."""

from __future__ import annotations

import pytest

from capmj.agents.report.relations.picks import goal_numbers, ungrounded

MIXED = [{"kind": "block", "color": c} for c in ("blue", "blue", "green", "orange")] + [
    {"kind": "zone", "color": "orange"}]
ONE_COLOUR = [{"kind": "block", "color": "purple"}] * 8 + [{"kind": "zone", "color": "gray"}]


@pytest.mark.parametrize(("code", "goal", "says"), [
    ('require_stack(blocks(color="orange"), zone("orange"))', "Stack all blocks in the orange zone.",
     'in the goal "orange" names the orange zone, not the blocks'),
    ('require_inside(blocks(color=["yellow"]), zone("yellow"))', "Stack only the warm blocks in the yellow zone.",
     'names the yellow zone'),
    ('require_count(blocks(color="green"), zone(), 3)', "Stack the blocks of the commonest colour in the zone.",
     'the goal names no colour "green"'),
    ('for b in blocks("red"):\n    require_outside(b, bowl("blue"))', "Put the blocks in bowls of other colours.",
     'the goal names no colour "red"'),
    # a list that leaves a colour of the scene out still guesses
    ('require_alternating(blocks(color=["blue", "green"]), first_color="blue")',
     "Stack the blocks with alternate colours, starting with blue.", 'the goal names no colour "green"'),
    ("require_count(blocks(), zone(), 3)", "Put the most blocks you can in the zone.", "the goal says no number 3"),
    ("require_count(blocks(), zone(), n=5)", "Put two blocks in the zone.", "the goal says no number 5"),
])
def test_a_literal_the_goal_does_not_give_is_named(code: str, goal: str, says: str) -> None:
    problem = ungrounded(code, goal, MIXED)
    assert problem is not None and says in problem


@pytest.mark.parametrize(("code", "goal", "rows"), [
    # the colour is said of blocks too
    ('require_inside(blocks(color="orange"), zone("orange"))', "Put the orange blocks in the orange zone.", MIXED),
    ('require_stack(blocks(color=["blue", "green"]))', "Stack the blue and green blocks.", MIXED),
    # the colour of a place: the "matching colour" reading
    ('require_inside(blocks(color="orange"), zone("orange"))', "Put the blocks in the zones of their colour.", MIXED),
    # a colour computed from the scene, not written
    ('for z in zones():\n    require_inside(blocks(color=z["color"]), z)', "Put each block in its zone.", MIXED),
    # the only colour the blocks have: picking it picks them all
    ('require_layers(blocks(color="purple"), [4, 4])', "Build a cube of 8 blocks of one colour.", ONE_COLOUR),
    # a list of every colour the blocks have: all blocks, nothing guessed
    ('require_alternating(blocks(color=["blue", "green", "orange"]), first_color="blue")',
     "Stack the blocks with alternate colours, starting with blue.", MIXED),
    # temperature and size words are not colours
    ('require_stack(blocks(color="warm", size="big"))', "Stack the big warm blocks.", MIXED),
    ('require_stack(blocks(color="big"))', "Stack the bigger blocks.", MIXED),
    # counts the goal says, in digits or words, and 0/1, which it need not spell
    ("require_count(blocks(), zone(), 2)", "Put two blocks in the zone.", MIXED),
    ("require_count(blocks(), zone(), 14)", "Build a 9-4-1 pyramid of 14 blocks.", MIXED),
    ("require_count(blocks(), zone(), 0)", "Keep every block out of the zone.", MIXED),
    ("n = len(blocks())\nrequire_count(blocks(), zone(), n)", "Put all blocks in the zone.", MIXED),
    ("require_inside(blocks(, zone())", "Stack the blue blocks.", MIXED),  # not Python: the sandbox reports it
])
def test_what_the_goal_says_or_the_check_computes_passes(code: str, goal: str, rows: list[dict[str, str]]) -> None:
    assert ungrounded(code, goal, rows) is None


def test_goal_numbers_reads_digits_and_number_words() -> None:
    assert goal_numbers("Construct a 2*2*2 cube using eight blocks") == {0, 1, 2, 8}
    assert goal_numbers("groups of 3 (also the group with block number less than 3)") == {0, 1, 3}
