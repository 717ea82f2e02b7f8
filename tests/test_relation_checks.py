"""The pre-bound relation checks of the ``relations`` reporter (:mod:`capmj.agents.report.relations.checks`),
on hand-built records: each relation holds where it should, fails where it should, and names the
objects that break it; bad arguments raise CheckArgumentError naming the valid choices."""

from __future__ import annotations

from typing import Any

import pytest

from capmj.agents.report.relations.checks import CHECKS, NAMES, relation_env
from capmj.agents.sandbox import run_code
from capmj.errors import CheckArgumentError, PlanError, describe


def block(i: int, color: str, centre: tuple[float, float, float], *, size: str = "small", level: int = 1,
          rests_on: str = "table", inside: str = "", tilted: bool = False, area: str = "top left",
          start_area: str = "top left") -> dict[str, Any]:
    return {"name": f"movable {size} {color} block with obj_id {i}", "kind": "block", "color": color, "size": size,
            "area": area, "start_area": start_area, "rests_on": rests_on, "below": [], "level": level,
            "inside": inside, "inside_color": "", "holds": [], "tilted": tilted, "centre": list(centre)}


def place(i: int, kind: str, color: str, centre: tuple[float, float, float] = (0.5, 0.2, 0.0)) -> dict[str, Any]:
    return {"name": f"{color} {kind} with obj_id {i}", "kind": kind, "color": color, "size": None, "area": "top right",
            "start_area": "top right", "rests_on": "table", "below": [], "level": 1, "inside": "",
            "inside_color": "", "holds": [], "tilted": False, "centre": list(centre)}


ZONE = "green zone with obj_id 1"


def tower(colors: list[str], *, inside: str = ZONE) -> list[dict[str, Any]]:
    out: list[dict[str, Any]] = []
    for k, c in enumerate(colors):
        out.append(block(k + 2, c, (0.5, 0.2, 0.02 + 0.04 * k), level=k + 1, inside=inside,
                         rests_on=out[-1]["name"] if out else "table"))
    return out


def run(rows: list[dict[str, Any]], code: str, start: list[dict[str, Any]] | None = None) -> tuple[bool, list[str], str]:
    env, failures = relation_env(rows, start)
    run_code(code, env)
    assert failures.calls > 0
    return not failures.items, sorted(failures.wrong), failures.reason


def test_a_tower_in_its_zone_passes_and_a_block_off_it_is_named() -> None:
    rows = [place(1, "zone", "green"), *tower(["red", "blue", "red"])]
    assert run(rows, "require_inside(blocks(), zone('green'))\nrequire_stack(blocks())\n"
                     "require_alternating(blocks(), first_color='red')")[0]
    off = [*rows[:3], block(4, "red", (0.6, -0.2, 0.02))]
    ok, wrong, reason = run(off, "require_stack(blocks(), zone('green'))")
    assert not ok and wrong == [off[3]["name"]] and "not in the green zone" in reason and "stack" in reason
    ok, wrong, _ = run(rows, "require_alternating(blocks(), first_color='blue')")
    assert not ok and wrong == [rows[1]["name"]]  # the bottom block has the wrong colour


def test_two_towers_are_not_one_stack() -> None:
    rows = [place(1, "zone", "green"), *tower(["red", "blue"]),
            block(4, "red", (0.55, 0.2, 0.02), inside=ZONE), block(5, "blue", (0.55, 0.2, 0.06), level=2, inside=ZONE,
                                                                  rests_on="movable small red block with obj_id 4")]
    ok, wrong, _ = run(rows, "require_stack(blocks())")
    assert not ok and set(wrong) == {rows[3]["name"], rows[4]["name"]}
    assert run(rows, "require_layers(blocks(), [2, 2])")[0]
    assert not run(rows, "require_layers(blocks(), [3, 1])")[0]


def test_selectors_read_colour_words_sizes_start_areas_and_sides() -> None:
    rows = [block(1, "red", (0.3, -0.2, 0.02), size="big", start_area="top left"),
            block(2, "blue", (0.3, 0.1, 0.02), start_area="top right"),
            block(3, "yellow", (0.6, 0.3, 0.02), size="big", start_area="bottom right")]
    env, _ = relation_env(rows)
    names = lambda rs: [r["color"] for r in rs]  # noqa: E731
    assert names(env["blocks"](color="warm")) == ["red", "yellow"]
    assert names(env["blocks"](color="cool")) == ["blue"]
    assert names(env["blocks"](color=["warm"])) == ["red", "yellow"]
    assert names(env["blocks"](size="bigger")) == ["red", "yellow"]
    assert names(env["blocks"](start_area="top right")) == ["blue"]
    assert names(env["other_blocks"](env["blocks"](color="red"))) == ["blue", "yellow"]
    assert names(env["blocks_beside"](rows[0], "right", 0.05)) == ["blue", "yellow"]
    assert names(env["blocks_beside"](rows[0], "right", 0.35)) == ["yellow"]
    assert names(env["blocks_beside"](rows[0], "front", 0.1)) == ["yellow"]


def test_places_may_be_areas_colour_words_or_any_of_a_list() -> None:
    bowls = [place(1, "bowl", "red"), place(2, "bowl", "blue")]
    rows = [*bowls, block(3, "red", (0.5, 0.2, 0.03), inside=bowls[1]["name"], area="bottom right"),
            block(4, "blue", (0.5, -0.2, 0.03), area="bottom left")]
    ok, wrong, _ = run(rows, "require_inside(blocks(), bowls())")
    assert not ok and wrong == [rows[3]["name"]]
    assert run(rows, "require_outside(blocks(color='red'), bowl('red'))")[0]
    assert run(rows, "require_inside(blocks(color='red'), 'blue bowl')")[0]
    assert run(rows, "require_inside(blocks(color='blue'), 'bottom left')")[0]
    assert run(rows, "require_count(blocks(), bowls(), 1)")[0]
    assert not run(rows, "require_count(blocks(), bowls(), 2)")[0]


def test_circles_rows_unmoved_and_distinct_colours() -> None:
    import math

    ring = [block(i + 1, "red" if i % 2 else "blue", (0.5 + 0.1 * math.cos(i * math.pi / 3),
                                                      0.1 * math.sin(i * math.pi / 3), 0.02)) for i in range(6)]
    ball = {**place(9, "ball", "white", (0.5, 0.0, 0.02)), "kind": "ball"}
    assert run([*ring, ball], "require_circle(blocks(), around=ball())\nrequire_alternating(blocks())")[0]
    assert run([*ring, ball], "require_alternating(blocks(), around=ball())")[0]  # ordered around the ball
    assert not run([*ring[:4], {**ring[4], "color": "red"}, ring[5], ball], "require_alternating(blocks(), around=ball())")[0]
    bent = [*ring[:5], {**ring[5], "centre": [0.5, -0.02, 0.02]}]
    ok, wrong, _ = run(bent, "require_circle(blocks())")
    assert not ok and wrong == [ring[5]["name"]]
    assert not run([*ring, {**ball, "centre": [0.6, 0.1, 0.02]}], "require_circle(blocks(), around=ball())")[0]
    row = [block(i + 1, "red", (0.4 + 0.05 * i, 0.1, 0.02)) for i in range(4)]
    assert run(row, "require_row(blocks())")[0]
    assert not run(ring, "require_row(blocks())")[0]
    moved = [{**row[0], "centre": [0.4, 0.2, 0.02]}, *row[1:]]
    ok, wrong, _ = run(moved, "require_unmoved(blocks())", start=row)
    assert not ok and wrong == [row[0]["name"]]
    ok, wrong, _ = run(row, "require_different_colors(blocks())")
    assert not ok and len(wrong) == 3


@pytest.mark.parametrize(("code", "needle"), [
    # a colour some object has may be a loop over colours: not read as the only zone
    ("require_inside(blocks(), zone('red'))", "the zones here are ['green']: the only zone is the green one, "
                                              "zone() picks it"),
    ("require_inside(blocks(), bowl('purple'))", "the bowls here are []: loop over bowls()"),
    ("require_inside(blocks(), 'the table')", "is not a place"),
    ("blocks(size='huge')", "valid: big, bigger"),
    ("blocks_beside(blocks()[0], 'above')", "valid: left, right, front, rear"),
    ("require_stack(['no such block'])", "is not an object of this scene"),
])
def test_bad_arguments_name_the_valid_choices(code: str, needle: str) -> None:
    env, _ = relation_env([place(1, "zone", "green"), *tower(["red"])])
    with pytest.raises(PlanError, match="ValueError") as err:
        run_code(code, env)
    assert needle in str(err.value)


AREAS_SAID = "['top left', 'top right', 'bottom left', 'bottom right', 'outside the workspace']"


@pytest.mark.parametrize(("code", "message"), [
    ("require_inside(None, zone('green'))", "objects is None: pick objects with blocks(...) or a list of records"),
    ("require_stack(['no such block'])",
     "'no such block' is not an object of this scene: pass records from blocks(...) or objects, or their full names"),
    ("require_inside(blocks(), 'the table')",
     "'the table' is not a place: use zone(color), bowl(color), zones(), bowls(), one of ['green zone with obj_id 1', "
     f"'pink zone with obj_id 2', 'red bowl with obj_id 3'] or an area {AREAS_SAID}"),
    ("zone()", "there is no single zone (there are 2); the zones here are ['green', 'pink']: loop over zones() to "
               "visit only those that exist"),
    ("bowl('green')", "there is no green bowl; the bowls here are ['red']: the only bowl is the red one, bowl() picks it"),
    ("ball()", "there is no single ball (there are 0); the balls here are []"),
    ("blocks(size='huge')", "size 'huge': valid: big, bigger, large, small, smaller, tiny"),
    ("blocks(start_area='middle')",
     "start_area 'middle': valid: top left, top right, bottom left, bottom right, outside the workspace"),
    ("blocks_beside(blocks()[0], 'above')", "side 'above': valid: left, right, front, rear"),
])
def test_a_bad_argument_is_a_check_argument_error_shown_as_it_always_was(code: str, message: str) -> None:
    """The kind is a class (:class:`CheckArgumentError`), not a prefix of the message; the text the repair
    request quotes is, to the character, the one ``PlanError("ValueError: ...")`` showed.  Not a
    ``ValueError``: a check's ``except ValueError`` does not catch it, as it never did."""
    rows = [place(1, "zone", "green"), place(2, "zone", "pink"), place(3, "bowl", "red"), *tower(["red"])]
    env, _ = relation_env(rows)
    with pytest.raises(PlanError) as err:
        run_code(f"try:\n    {code}\nexcept ValueError:\n    pass", env)
    cause = err.value.__cause__
    assert isinstance(cause, CheckArgumentError) and isinstance(cause, PlanError) and not isinstance(cause, ValueError)
    assert str(cause) == message
    assert describe(cause) == f"PlanError: ValueError: {message}"
    assert describe(err.value) == f"PlanError: line 2: PlanError: ValueError: {message}"


def test_a_call_with_missing_arguments_names_the_check_as_the_prompt_does() -> None:
    env, _ = relation_env([place(1, "zone", "green"), *tower(["red"])])
    with pytest.raises(PlanError, match=r"TypeError: require_count\(\) missing 1 required positional argument: 'n'"):
        run_code("require_count(blocks(), zone())", env)


def test_every_check_is_bound_and_counted() -> None:
    env, failures = relation_env([place(1, "zone", "green"), *tower(["red", "blue"])])
    assert tuple(env) == NAMES and set(CHECKS) <= set(env)
    run_code("require_on_table(blocks())\nrequire_stack(blocks())", env)
    assert failures.calls == 2 and failures.wrong == ("movable small blue block with obj_id 3",)


def test_small_model_slips_are_read_kindly_and_empty_picks_noted() -> None:
    """``blocks(color="big")`` means the size; ``b.color`` reads the key; ``zone("zone")`` is the only zone;
    a pick of no block is noted for the repair request (a relation over nothing holds)."""
    rows = [place(1, "zone", "orange"), block(2, "red", (0.3, -0.2, 0.02), size="big"), block(3, "blue", (0.3, 0.1, 0.02))]
    env, _ = relation_env(rows)
    assert [r["color"] for r in env["blocks"](color="big")] == ["red"]
    assert run_code("c = [b.color for b in blocks()]", env)["c"] == ["red", "blue"]
    assert env["zone"]("zone")["color"] == "orange"  # the kind word where a colour goes: the only zone
    assert env["zone"]("purple")["color"] == "orange"  # a colour nothing here has (an example's): the only zone
    with pytest.raises(PlanError, match="there is no purple bowl"):
        env["bowl"]("purple")  # no bowl at all: nothing to read it as
    env, failures = relation_env(rows)
    run_code("require_stack(blocks(color='orange'), zone('orange'))", env)
    assert not failures.items and "picks no block: the blocks here have the colours ['blue', 'red']" in failures.empty_picks[0]


@pytest.mark.parametrize(("code", "why"), [
    ("require_count(blocks(color='red'), zone('green'), 2)", "requires 2 of 1 objects"),
    ("require_layers(blocks(), [2, 2])", "layers of [2, 2] of 2 objects"),
    ("require_inside(blocks(), zone('green'))\nrequire_outside(blocks(color='red'), zone('green'))", "both in and out"),
    ("require_inside(blocks(), zone('green'))\nrequire_inside(blocks(color='red'), bowl('red'))", "two different places"),
    ("require_stack(blocks())\nrequire_on_table(blocks())", "one tower and all on the table"),
    ("require_stack(blocks())\nrequire_layers(blocks(), [1, 1])\nrequire_layers(blocks(), [2])", "layers of several"),
])
def test_calls_no_scene_can_pass_together_are_found(code: str, why: str) -> None:
    rows = [place(1, "zone", "green"), place(4, "bowl", "red"), *tower(["red", "blue"])]
    env, failures = relation_env(rows)
    run_code(code, env)
    assert why in (failures.impossible() or "")


def test_calls_a_scene_can_pass_together_are_not_impossible() -> None:
    rows = [place(1, "zone", "green"), place(4, "bowl", "red"), *tower(["red", "blue"])]
    env, failures = relation_env(rows)
    run_code("require_inside(blocks(), zones())\nrequire_inside(blocks(color='red'), zone('green'))\n"
             "require_stack(blocks(), zone('green'))\nrequire_layers(blocks(), [1, 1])\nrequire_on_table(blocks(color='red'))\n"
             "require_count(blocks(), zone('green'), 2)\nrequire_outside(blocks(), bowl('red'))\n"
             "require_inside(blocks(), 'top left')", env)
    assert failures.impossible() is None


def test_the_impossible_sentence_does_not_vary_with_string_hashing() -> None:
    """The sentence goes into the repair request, whose text keys the completion cache: with the names
    of a frozenset in hash order, reruns of the same judge set missed the cache and changed errors."""
    import subprocess
    import sys

    script = ("import sys; sys.path.insert(0, 'tests')\n"
              "from test_relation_checks import place, tower\n"
              "from capmj.agents.report.relations.checks import relation_env\n"
              "from capmj.agents.sandbox import run_code\n"
              "env, f = relation_env([place(1, 'zone', 'green'), place(4, 'bowl', 'red'), *tower(list('abcdefgh'))])\n"
              "run_code(\"require_inside(blocks(), zone('green'))\\nrequire_inside(blocks(), bowl('red'))\", env)\n"
              "print(f.impossible())\n")
    said = {subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True,
                           env={**__import__("os").environ, "PYTHONHASHSEED": str(seed)}).stdout for seed in range(4)}
    assert len(said) == 1 and "obj_id 2 in two different places" in said.pop()


def test_a_tower_also_required_in_layers_of_several_can_be_read_as_its_place() -> None:
    """``Failures.layered_towers`` finds the group; with it, ``require_stack`` asks only for the place."""
    base = [block(i + 2, "red", (0.5 + 0.05 * i, 0.2, 0.02), inside=ZONE) for i in range(2)]
    top = block(4, "red", (0.525, 0.2, 0.06), level=2, inside=ZONE, rests_on=base[0]["name"])
    rows = [place(1, "zone", "green"), *base, top]
    check = "require_stack(blocks(), zone('green'))\nrequire_layers(blocks(), [2, 1])"
    env, failures = relation_env(rows)
    run_code(check, env)
    assert failures.items and "layers of several" in (failures.impossible() or "")
    layered = failures.layered_towers()
    assert layered == {frozenset(r["name"] for r in rows[1:])}
    env, failures = relation_env(rows, layered=layered)
    run_code(check, env)
    assert not failures.items and failures.impossible() is None
    out = [place(1, "zone", "green"), *base, {**top, "inside": ""}]
    env, failures = relation_env(out, layered=layered)
    run_code(check, env)
    assert failures.wrong == (top["name"],)  # the place still holds for every block
    env, failures = relation_env(rows)
    run_code("require_stack(blocks())\nrequire_layers(blocks(), [1, 1, 1])", env)
    assert not failures.layered_towers()  # one block a layer is a tower: no contradiction to read
