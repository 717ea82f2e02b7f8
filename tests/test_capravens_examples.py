"""benchmarks/capravens_examples.py on prompt files written here in the original's layout (not its
text): how it splits examples and how it classifies each kind of outcome on real scenes."""

from __future__ import annotations


import pytest
from module_loader import ROOT, load_module


PLANNER = """# header the harness skips
# ---------------------------------------------------------------------------
# Task Examples
# ---------------------------------------------------------------------------

objects = ['red block with obj_id 1', 'green zone with obj_id 2']
# put the red block in the green zone.
put_first_on_second('red block with obj_id 1', 'green zone with obj_id 2')

objects = ['red block with obj_id 1', 'green bowl with obj_id 2']
# move the bowl away.
put_first_on_second('green bowl with obj_id 2', [0.5, 0.3])
objects = ['red block with obj_id 1', 'green zone with obj_id 2']
# say something broken.
say('it isn't')

objects = ['red block with obj_id 1', 'green zone with obj_id 2']
# put the block next to the zone.
p = get_obj_pos('green zone with obj_id 2')[0]
put_first_on_second('red block with obj_id 1', [p[0] + 0.1, p[1]])

objects = ['red block with obj_id 1', 'green zone with obj_id 2']
# make a zigzag.
pts = make_zigzag(3)

objects = ['red block with obj_id 1', 'small blue cylinder with obj_id 2']
# put the cylinder on the block.
cyl = parse_obj_name('the cylinder, return result as one str', f'objects = {get_obj_names()}')
put_first_on_second(cyl, 'red block with obj_id 1')

# ---------------------------------------------------------------------------
# Question
# ---------------------------------------------------------------------------
"""

CHECKER = """object_positions = {
    'red block with obj_id 1': [(0.5, 0.0, 0.02), (0, 0, 0)],
    'green zone with obj_id 2': [(0.5, 0.0, 0.0), (0, 0, 0)]}
# the red block is on the table
judge = object_positions['red block with obj_id 1'][0][2] < 0.05
"""


@pytest.fixture(scope="module")
def harness():
    return load_module(ROOT / "benchmarks" / "capravens_examples.py", register=True)


def test_split_keeps_contexts_queries_and_code(harness):
    examples = harness.split_examples("planner", PLANNER)
    assert [e.id for e in examples] == [f"planner#{i}" for i in range(1, 7)]
    assert examples[1].query == "# move the bowl away." and examples[2].query == "# say something broken."
    assert examples[3].code.count("\n") == 2 and examples[3].context.startswith("objects = ")
    (check,) = harness.split_examples("parse_completion", CHECKER)
    assert check.context.count("\n") == 2 and check.query == "# the red block is on the table"
    assert harness.context_names(check) == ["red block with obj_id 1", "green zone with obj_id 2"]


def test_read_original_from_a_work_tree(harness, tmp_path):
    (tmp_path / "prompts" / "capravens").mkdir(parents=True)
    (tmp_path / "prompts" / "capravens" / "prompt_tabletop_ui.txt").write_text(PLANNER)
    assert harness.read_original(tmp_path, harness.FILES["planner"]) == PLANNER


def test_each_outcome_gets_its_class(harness):
    examples = harness.split_examples("planner", PLANNER)
    got = {e.id: harness.classify(e, 10001, {}) for e in examples}
    assert got["planner#1"] == ("unchanged", "")
    assert got["planner#2"][0] == "mapping" and "is fixed and cannot be picked" in got["planner#2"][1]
    assert got["planner#3"][0] == "invalid_in_original" and "SyntaxError" in got["planner#3"][1]
    assert got["planner#4"][0] == "mapping" and "one-element list" in got["planner#4"][1]
    assert got["planner#5"][0] == "invalid_in_original" and "make_zigzag" in got["planner#5"][1]
    assert got["planner#6"] == ("fails", "uses cylinder objects, a kind capmj does not have")
    (check,) = harness.split_examples("parse_completion", CHECKER)
    assert harness.classify(check, 10001, {}) == ("unchanged", "")  # near-miss keys of object_positions


CHECK_AND_RETRY = """# Task Examples
# ---------------------------------------------------------------------------

objects = ['red block with obj_id 1', 'green zone with obj_id 2', 'blue block with obj_id 3']
# put the red block in the green zone, check, and try again.
put_first_on_second('red block with obj_id 1', [0.4, 0.3])
if not parse_completion('the red block in the green zone', f'object_positions = {get_obj_pos_dict()}'):
    reset()
    assert np.linalg.norm(np.array(get_obj_pos('red block with obj_id 1'))[:2] - [0.4, 0.3]) > 0.03
    put_first_on_second('red block with obj_id 1', 'green zone with obj_id 2')
box = get_bbox(['blue block with obj_id 3', 'red block with obj_id 1'])
assert box == get_bbox('blue block with obj_id 3')
"""


def test_a_plan_that_checks_itself_resets_and_retries_runs_unchanged(harness):
    """The scripted check answers False first: the retry branch runs, and reset() really brought
    the block back (the example's own assert), on the real world."""
    (plain,) = harness.split_examples("planner", CHECK_AND_RETRY.split("box = ")[0])
    assert harness.classify(plain, 10001, {}) == ("unchanged", "")
    (ex,) = harness.split_examples("planner", CHECK_AND_RETRY)  # + get_bbox of a list: its first object's box
    cls, reason = harness.classify(ex, 10001, {})
    assert cls == "mapping" and "reads get_bbox as CapRavens' sizes" in reason  # it ran; the numbers differ
