"""Relations a goal names that a check never asks for (capmj.agents.report.relations.reporter): each word
finds the partial check it is for, and a check that asks for every named relation passes."""

from __future__ import annotations

import pytest

from capmj.agents.report.relations.reporter import uncovered


@pytest.mark.parametrize(("code", "goal", "says"), [
    ('require_inside(blocks(), zone("red"))', "Stack all blocks in the red zone.", "no call asks for a stack"),
    ("require_stack(blocks())", "Stack all blocks in the red zone.", "where the objects must be"),
    ("require_alternating(blocks())", "Build a ring of blocks around the ball, colours alternating.",
     "no call asks for a circle"),
    ("require_circle(blocks())", "Build a ring of blocks around the ball, colours alternating.",
     "alternating colours"),
    ("require_stack(blocks())", "Put the cubes into each bowl of their colour.", 'the goal says "into each bowl"'),
    # a structure is layers, and its repair asks for them instead of the tower
    ('require_stack(blocks(), zone())', "Build a 3-2 wall structure in the zone.",
     "no call asks for layers (a structure has several blocks in a layer; a tower is one column): write "
     "require_layers(objs, [n1, n2, ...])"),
    ('require_inside(blocks(), zone())', "Put one more layer of blocks on the wall in the zone.",
     'the goal says "layer"'),
])
def test_a_relation_the_goal_names_and_the_check_leaves_out_is_named(code: str, goal: str, says: str) -> None:
    problem = uncovered(code, goal)
    assert problem is not None and says in problem


@pytest.mark.parametrize(("code", "goal"), [
    ('require_stack(blocks(), zone("red"))', "Stack all blocks in the red zone."),  # a placed stack places
    ('require_inside(blocks(), zone("red"))\nrequire_layers(blocks(), [2, 1])', "Stack a 2-1 wall in the red zone."),
    ("require_count(blocks(), bowl(), 2)", "Put two blocks in the bowl."),
    ('require_inside(blocks(), zone())\nrequire_layers(blocks(), [3, 2])', "Build a 3-2 wall structure in the zone."),
    ("require_outside(blocks(), zones())", "Keep the blocks on the table, not on the zone."),
    ("require_circle(blocks(), around=ball())\nrequire_alternating(blocks())",
     "Build a circle around the ball with alternating colours."),
    ('require_inside(blocks(start_area="top left"), "bottom right")', "Move the blocks in the top left area to the "
                                                                      "bottom right area."),
    ("require_stack(blocks(, zone())", "Stack the blocks."),  # not Python: the sandbox reports it
])
def test_a_check_that_asks_for_every_named_relation_passes(code: str, goal: str) -> None:
    assert uncovered(code, goal) is None
