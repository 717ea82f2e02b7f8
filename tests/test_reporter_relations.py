"""The ``relations`` reporter prompt (issue #26 item 3): the model writes the goal as calls of
pre-bound relation checks; capmj measures them on the final and the start scene.

States are real settled MuJoCo states of the judge set; the answers come from the scripted local
HTTP server (tests/llm_stub_server.py): fixtures that read the prompt, not results.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from llm_stub_server import StubLLMServer, prompt_text

from capmj.agents.prompt_files import load_prompt
from capmj.agents.report.relations.checks import CHECKS, SELECTORS
from capmj.agents.report.registry import make_reporter
from capmj.agents.report.relations.reporter import BLIND, HOLDS_AT_START, IMPOSSIBLE, RelationsReporter
from capmj.bench.cli import main
from capmj.errors import PlanError, UnknownCheckError, describe

SEED = 10001
BOWLS = "put-block-into-matching-bowl"
MATCHING = "for b in bowls():\n    require_inside(blocks(color=b['color']), b)"
"""A human's check of "Put the blocks in the bowls with matching colors." (the scene has one distractor)."""


def code(text: str) -> str:
    return f"```python\n{text.strip()}\n```"


def judge(tmp_path: Path, server: StubLLMServer, kinds: str, task: str = BOWLS) -> list[dict[str, Any]]:
    out = tmp_path / "out"
    rc = main(["judge", "--tasks", task, "--seeds", str(SEED), "--kinds", kinds, "--out", str(out), "--no-progress",
               "--reporter", "text", "--reporter-prompt", "relations", "--model", "openai/stub", "--api-base",
               server.base_url, "--llm-timeout", "10"])
    assert rc == 0
    assert json.loads((out / "summary.json").read_text())["reporter_prompt"] == "relations"
    return [json.loads(line) for line in (out / "judged.jsonl").read_text().splitlines()]


def test_the_goal_as_relations_agrees_with_the_predicate_and_names_what_is_wrong(server: StubLLMServer,
                                                                                tmp_path: Path) -> None:
    """One question per episode (goal + unchanging keys); each state's verdict follows its label, and
    every "not achieved" names a movable object (high confidence)."""
    prompts: list[str] = []

    def answer(request: dict[str, Any]) -> str:
        prompts.append(prompt_text(request))
        return code(MATCHING)

    server.respond_with(answer)
    judged = judge(tmp_path, server, "oracle,displaced,wrong_bowl,near_outside")
    assert len(judged) >= 3 and any(not r["label"] for r in judged)
    for r in judged:
        assert (r["source"], r["verdict"], r["confidence"]) == ("code", r["label"], "high"), r
        assert bool(r["wrong"]) == (not r["label"]) and all(w.startswith("movable") for w in r["wrong"])
    assert len(set(prompts)) == 1
    assert "'inside'" not in prompts[0].split("# The objects of this scene.")[1]  # no measured key is shown
    assert "require_stack(objs, place=None)" in prompts[0] and "# goal: Put the blocks in the bowls" in prompts[0]


def test_a_made_up_check_is_refused_with_the_valid_names_not_written_by_parse_function(server: StubLLMServer,
                                                                                      tmp_path: Path) -> None:
    server.respond_with(lambda request: code(
        MATCHING if "is not defined" in prompt_text(request) else "require_matching_bowls(blocks())"))
    judged = judge(tmp_path, server, "oracle,displaced")
    assert len(server.requests) == 2 * len(judged)  # the answer and its repair: no parse_function call
    repair = prompt_text(server.requests[1])
    assert "require_matching_bowls is not defined" in repair and all(c in repair for c in CHECKS)
    assert [(r["verdict"], r["source"]) for r in judged] == [(r["label"], "repair") for r in judged]


def test_a_made_up_check_is_an_unknown_check_error_shown_as_it_always_was(server: StubLLMServer, tmp_path: Path,
                                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """The kind is a class (:class:`UnknownCheckError`, not a ``NameError``); the repair request quotes, to
    the character, what ``PlanError("NameError: ...")`` showed."""
    import capmj.agents.report.relations.reporter as reporter

    seen: list[BaseException] = []

    def spy(exc: BaseException) -> str:
        seen.append(exc)
        return describe(exc)

    monkeypatch.setattr(reporter, "describe", spy)
    server.respond_with(lambda request: code(
        MATCHING if "is not defined" in prompt_text(request) else "require_matching_bowls(blocks())"))
    judge(tmp_path, server, "oracle")
    error = seen[0]
    assert isinstance(error, UnknownCheckError) and isinstance(error, PlanError) and not isinstance(error, NameError)
    shown = (f"PlanError: NameError: require_matching_bowls is not defined; the checks are {', '.join(CHECKS)} "
             f"and the selectors {', '.join(SELECTORS)}")
    assert describe(error) == shown
    assert f"# The checking code above failed: {shown}\n" in prompt_text(server.requests[1])


def test_a_check_without_a_required_relation_is_blind(server: StubLLMServer, tmp_path: Path) -> None:
    """``judge = False`` tests nothing: the repair request says so; repeated, the ``checked`` question decides."""
    server.respond_with(lambda request: code("judge = False"))
    judged = judge(tmp_path, server, "oracle")
    assert BLIND in prompt_text(server.requests[1])
    assert [(r["source"], r["low_confidence"], r["errors"][:2]) for r in judged] == [
        ("direct", "direct_fallback", [f"code: {BLIND}", f"repair: {BLIND}"])]


def test_a_check_that_holds_at_the_start_is_repaired_then_doubted(server: StubLLMServer, tmp_path: Path) -> None:
    """Requiring only that the blocks stand on the table holds at the start, where no goal holds."""
    server.respond_with(lambda request: code("require_on_table(blocks())"))
    judged = judge(tmp_path, server, "oracle,displaced")
    assert HOLDS_AT_START in prompt_text(server.requests[1])
    for r in judged:
        assert (r["source"], r["low_confidence"], r["errors"]) == ("repair", "holds_at_start",
                                                                   [f"code: {HOLDS_AT_START}"]), r
    server.respond_with(lambda request: code(MATCHING if HOLDS_AT_START in prompt_text(request)
                                             else "require_on_table(blocks())"))
    judged = judge(tmp_path / "repaired", server, "oracle,displaced")
    assert [(r["verdict"], r["source"], r["confidence"]) for r in judged] == [
        (r["label"], "repair", "high") for r in judged]


def test_the_prompt_examples_run_and_relations_is_a_text_prompt() -> None:
    """Every example of ``prompts/reporter_relations.py`` calls only documented names (each is valid Python)."""
    import ast

    text = load_prompt("reporter_relations").template
    bodies = [part.split("\n\n")[0] for part in text.split("# goal: ")[1:]]
    assert len(bodies) >= 6
    for body in bodies:
        tree = ast.parse(body.split("\n", 1)[1])
        called = {n.func.id for n in ast.walk(tree) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}
        assert called & set(CHECKS), body
    assert isinstance(make_reporter("text", None, "relations"), RelationsReporter)


def test_calls_no_scene_can_pass_are_repaired_then_doubted(server: StubLLMServer, tmp_path: Path) -> None:
    """Two of a colour of which the scene has one: "not achieved" of every state, yet naming objects;
    the repair request says so, and repeated, the verdict is low-confidence (``impossible_check``)."""
    server.respond_with(lambda request: code("for b in bowls():\n    require_count(blocks(color=b['color']), b, 2)"))
    judged = judge(tmp_path, server, "oracle,displaced")
    assert IMPOSSIBLE in prompt_text(server.requests[1])
    for r in judged:
        assert (r["verdict"], r["source"], r["low_confidence"]) == (False, "repair", "impossible_check"), r


def test_a_zone_colour_read_as_the_blocks_gets_a_repair_that_says_what_the_colour_names(server: StubLLMServer,
                                                                                       tmp_path: Path) -> None:
    """"Stack all blocks in the orange zone" read as the orange blocks: the goal says the colour only
    of the zone, so the repair request says so; the repaired check follows the labels (high confidence)."""
    def answer(request: dict[str, Any]) -> str:
        text = prompt_text(request)
        colour = text[text.rindex("# goal: "):].split(" zone")[0].split()[-1]
        if "not the blocks" in text:
            return code(f"require_stack(blocks(), zone('{colour}'))")
        return code(f"require_stack(blocks(color='{colour}'), zone('{colour}'))")

    server.respond_with(answer)
    judged = judge(tmp_path, server, "oracle,unstacked", task="stack-all-blocks-on-a-zone")
    repair = prompt_text(server.requests[1])
    assert " zone, not the blocks: pick the blocks the goal means" in repair and HOLDS_AT_START not in repair
    assert [(r["verdict"], r["source"], r["confidence"]) for r in judged] == [
        (r["label"], "repair", "high") for r in judged]


def test_a_pick_of_no_block_that_holds_at_start_gets_a_repair_naming_the_colours_that_exist(
        server: StubLLMServer, tmp_path: Path) -> None:
    """A colour computed from a place that no block has (the other zone): the pick is empty, the check holds at the
    start, and the repair request lists the blocks' real colours."""
    server.respond_with(lambda request: code("require_stack(blocks(color=zone('purple')['color']), zone('orange'))"))
    judged = judge(tmp_path, server, "oracle,unstacked", task="stack-all-blocks-on-a-zone")
    repair = prompt_text(server.requests[1])
    assert HOLDS_AT_START in repair and "picks no block: the blocks here have the colours [" in repair
    assert [(r["source"], r["low_confidence"]) for r in judged] == [("repair", "holds_at_start")] * len(judged)


def test_a_count_the_goal_does_not_give_is_repaired_then_doubted(server: StubLLMServer, tmp_path: Path) -> None:
    """A guessed count (the goal says no number): repaired, and repeated, kept low-confidence."""
    server.respond_with(lambda request: code(MATCHING + "\nrequire_count(blocks(), bowls(), 2)"))
    judged = judge(tmp_path, server, "oracle,displaced")
    assert "the goal says no number 2" in prompt_text(server.requests[1])
    assert [(r["source"], r["low_confidence"]) for r in judged] == [("repair", "ungrounded_literal")] * len(judged)


def test_a_relation_the_goal_names_and_the_check_leaves_out_is_repaired_then_doubted(server: StubLLMServer,
                                                                                      tmp_path: Path) -> None:
    """"Stack all blocks in the orange zone" checked as "inside" only: the repair request names the
    stack; repeated, the verdict is kept low-confidence (``misses_a_relation``); added, it follows the labels."""
    inside_only = "require_inside(blocks(), zone('orange'))"
    server.respond_with(lambda request: code(inside_only))
    judged = judge(tmp_path, server, "oracle,unstacked", task="stack-all-blocks-on-a-zone")
    assert 'the goal says "stack", but no call asks for a stack' in prompt_text(server.requests[1])
    assert [(r["source"], r["low_confidence"]) for r in judged] == [("repair", "misses_a_relation")] * len(judged)
    server.respond_with(lambda request: code(inside_only + ("\nrequire_stack(blocks())" if "asks for a stack" in
                                                            prompt_text(request) else "")))
    judged = judge(tmp_path / "repaired", server, "oracle,unstacked", task="stack-all-blocks-on-a-zone")
    assert [(r["verdict"], r["source"], r["confidence"]) for r in judged] == [
        (r["label"], "repair", "high") for r in judged]


def test_a_tower_also_required_in_layers_is_read_as_its_place(server: StubLLMServer, tmp_path: Path) -> None:
    """The pyramid as ``require_stack`` and ``require_layers`` of the same blocks (the 1.5B model's answer, kept
    after the impossible repair): no repair request, the layers say the shape, the tower its place, and the
    verdict follows the labels with high confidence."""
    server.respond_with(lambda request: code("require_stack(blocks(), zone())\nrequire_layers(blocks(), [9, 4, 1])"))
    judged = judge(tmp_path, server, "oracle,unstacked,toppled_out", task="build-rectangular-pyramid")
    assert len(server.requests) == len(judged) and {r["label"] for r in judged} == {True, False}
    assert not any("failed" in prompt_text(request) for request in server.requests)  # no repair request
    assert [(r["verdict"], r["source"], r["confidence"]) for r in judged] == [
        (r["label"], "code", "high") for r in judged]


def test_the_gates_are_values_the_reasons_follow_from_them_and_the_docs_say_why_each_exists() -> None:
    """Each reporter's gates have distinct keys; the low-confidence reasons are the rules of ``assess`` and
    the keys of the gates that keep a verdict doubted (none listed by hand); docs/judge.md's "Why each
    gate exists" table has a row for every gate, and the page lists every reason."""
    from capmj.agents.choices import REPORTER_TABLE
    from capmj.agents.report.confidence import RULES, low_confidence_reasons
    from capmj.agents.report.registry import load_reporter
    from capmj.agents.report.relations.reporter import BLIND_GATE, GATES

    gates = [g for prompts in REPORTER_TABLE.values() for e in prompts.values()
             for g in getattr(load_reporter(e.target), "gates", ())]
    assert [g.key for g in RelationsReporter.gates] == [BLIND_GATE.key] + [g.key for g in GATES]
    assert [g.key for g in GATES] == ["impossible_check", "ungrounded_literal", "holds_at_start", "misses_a_relation"]
    kept = {g.key: g.why for g in gates if g.keeps}
    assert low_confidence_reasons() == {**{r.key: r.why for r in RULES}, **kept}
    assert "blind" not in low_confidence_reasons()  # a blind answer is never kept: the fallback decides
    doc = (Path(__file__).resolve().parent.parent / "docs" / "judge.md").read_text(encoding="utf-8")
    table = doc.split("## Why each gate exists")[1].split("\n## ")[0]
    assert all(f"`{g.key}`" in table for g in gates), [g.key for g in gates if f"`{g.key}`" not in table]
    assert all(f"- `{key}`:" in doc for key in low_confidence_reasons())
