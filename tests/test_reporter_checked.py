"""The ``checked`` reporter prompt (issue #26 item 3): capmj binds the scene facts, the verdict names
the objects it finds wrong, and ``judge`` takes the prompt and a stratified subset.

The facts are checked on real settled MuJoCo states of the judge set; the reporter's answers come
from the scripted local HTTP server (tests/llm_stub_server.py): fixtures that read the prompt, not
results.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest
from llm_stub_server import StubLLMServer, prompt_text
from module_loader import ROOT

from capmj.agents.report.confidence import LOW_CONFIDENCE, assess
from capmj.agents.report.verdict import Report
from capmj.agents.report.scene import facts_text, resolve_name, scene_facts
from capmj.bench.cli import main
from capmj.judge.cases import JudgeCase, Stage
from capmj.judge.judgeset import build_cases
from capmj.judge.subset import stratified
from capmj.tasks.registry import get_task

SEED = 10001
TASKS = "stack-blocks-with-alternate-color,put-block-into-matching-bowl"
CHECKED = "You compare measured scene facts with a goal"


def code(text: str) -> str:
    return f"```python\n{text.strip()}\n```"


@pytest.fixture(scope="module")
def bowl_cases() -> tuple[Stage, list[JudgeCase]]:
    task = get_task("put-block-into-matching-bowl")
    return Stage(task, SEED), build_cases(task, SEED, kinds=("oracle", "displaced", "wrong_bowl"))[0]


def test_facts_follow_the_tasks_containment_rule_on_real_states(bowl_cases: tuple[Stage, list[JudgeCase]]) -> None:
    stage, cases = bowl_cases
    by_kind = {c.kind: c for c in cases}
    assert {"oracle", "displaced"} <= set(by_kind)
    solved = scene_facts(stage.realise(by_kind["oracle"].poses()))
    goal_blocks = [f for f in solved if f.kind == "block" and any("bowl" in n for n in f.inside)]
    assert goal_blocks, facts_text(solved)
    for f in goal_blocks:
        assert f.rests_on.endswith("(inside)") and f.tilt_deg < 15
    moved = by_kind["displaced"]
    facts = {f.name: f for f in scene_facts(stage.realise(moved.poses()))}
    changed = [name for name, f in facts.items() if f.inside != next(g for g in solved if g.name == name).inside]
    assert len(changed) == 1 and facts[changed[0]].inside == () and facts[changed[0]].rests_on == "the table"
    text = facts_text(list(facts.values()))
    assert f"- {changed[0]}: centre [" in text and "in no zone or bowl" in text and "holds:" in text


def test_names_resolve_to_real_objects_and_the_confidence_follows(bowl_cases: tuple[Stage, list[JudgeCase]]) -> None:
    objects = bowl_cases[0].world.objects
    block = next(o for o in objects if o.kind == "block")
    bowl = next(o for o in objects if o.kind == "bowl")
    assert resolve_name(block.name.upper(), objects) == block
    assert resolve_name(f"the thing with obj_id {block.obj_id}", objects) == block
    assert resolve_name("purple elephant", objects) is None
    cases = {
        "names_nothing": Report("text", False, "no", wrong=()),
        "names_no_real_object": Report("text", False, "no", wrong=("purple elephant",)),
        "names_only_fixed": Report("text", False, "no", wrong=(bowl.name,)),
        "achieved_but_names_wrong": Report("text", True, "yes", wrong=(block.name,)),
        "no_verdict": Report("text", None, ""),
        "direct_fallback": Report("text", False, "no", source="direct", wrong=(block.name,)),
        "copies_example": Report("text", False, "no", wrong=(block.name,), doubt="copies_example"),
        "holds_at_start": Report("text", True, "yes", doubt="holds_at_start"),
        "impossible_check": Report("text", False, "no", wrong=(block.name,), doubt="impossible_check"),
        "ungrounded_literal": Report("text", False, "no", wrong=(block.name,), doubt="ungrounded_literal"),
        "misses_a_relation": Report("text", True, "yes", doubt="misses_a_relation"),
    }
    for why, report in cases.items():
        a = assess(report, objects)
        assert (a.confidence, a.why) == ("low", why), why
    a = assess(Report("text", False, "no", wrong=(bowl.name, block.name)), objects)
    assert (a.confidence, a.why, a.wrong_ids) == ("high", None, (block.obj_id,))
    assert assess(Report("text", True, "yes"), objects).confidence == "high"
    assert set(cases) == set(LOW_CONFIDENCE)  # every reason is reachable


def judge(tmp_path: Path, *extra: str) -> tuple[int, dict[str, Any], list[dict[str, Any]]]:
    out = tmp_path / "out"
    rc = main(["judge", "--tasks", TASKS, "--seeds", str(SEED), "--out", str(out), "--no-progress", *extra])
    if rc != 0:
        return rc, {}, []
    return (rc, json.loads((out / "summary.json").read_text()),
            [json.loads(line) for line in (out / "judged.jsonl").read_text().splitlines()])


def test_judge_with_the_checked_prompt_sends_facts_and_records_the_confidence(server: StubLLMServer,
                                                                            tmp_path: Path) -> None:
    """A scripted answer that calls a state failed exactly when some block's fact line says it is in
    no zone or bowl, naming that block: the facts reach the model, names are checked."""
    prompts: list[str] = []

    def from_facts(request: dict[str, Any]) -> str:
        text = prompt_text(request)
        assert CHECKED in text and "Goal: " in text
        prompts.append(text)
        loose = re.findall(r"^- (movable [^:]+ block with obj_id \d+): .*in no zone or bowl", text, re.M)
        if loose:
            return code(f"judge = False\nreason = 'a block is outside'\nwrong = [{loose[0]!r}]")
        return code("judge = False\nreason = 'not sure'\nwrong = []")  # no object named: low confidence

    server.respond_with(from_facts)
    rc, s, judged = judge(tmp_path, "--reporter", "text", "--reporter-prompt", "checked", "--model", "openai/stub",
                          "--api-base", server.base_url, "--llm-timeout", "10", "--kinds", "oracle,displaced")
    assert rc == 0 and s["reporter"] == "text/checked openai/stub" and s["reporter_prompt"] == "checked"
    assert len(prompts) == len(judged) == s["overall"]["calls"]  # one request per state, no code executed
    assert all(r["reporter_prompt"] == "checked" and r["source"] == "code" for r in judged)
    for r in judged:
        if r["wrong"]:
            assert r["confidence"] == "high" and r["low_confidence"] is None, r
        else:
            assert (r["confidence"], r["low_confidence"]) == ("low", "names_nothing"), r
    bowls = [r for r in judged if r["task"] == "put-block-into-matching-bowl"]
    assert {r["kind"]: r["confidence"] for r in bowls} == {"oracle": "low", "displaced": "high"}
    assert s["overall"]["high_confidence"] == sum(r["confidence"] == "high" for r in judged)
    config = json.loads((tmp_path / "out" / "config.json").read_text())
    assert config["config"]["reporter_prompt"] == "checked"


def test_a_text_prompt_is_refused_for_the_vlm_reporter(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["judge", "--tasks", TASKS, "--seeds", str(SEED), "--out", str(tmp_path), "--reporter", "vlm",
                 "--model", "m", "--reporter-prompt", "checked"]) == 2
    assert "--reporter-prompt checked needs --reporter text" in capsys.readouterr().err
    assert main(["judge", "--tasks", TASKS, "--seeds", str(SEED), "--out", str(tmp_path), "--reporter", "predicate",
                 "--per-task", "0"]) == 2
    assert "--per-task must be >= 1" in capsys.readouterr().err


def _case(task: str, seed: int, kind: str) -> JudgeCase:
    return JudgeCase(task, seed, kind, kind, kind in ("oracle", "near_inside"), "", "", 1.0, ())


def test_the_stratified_subset_is_balanced_deterministic_and_in_set_order() -> None:
    kinds = ("oracle", "displaced", "unstacked", "toppled", "near_inside", "near_outside")
    cases = [_case(t, s, k) for t in ("a", "b") for s in (1, 3, 5, 7, 9) for k in kinds]
    cases += [_case("c", 1, "oracle"), _case("c", 1, "displaced")]  # a task with few cases: all of them
    four = stratified(cases, 4)
    for task in ("a", "b"):
        mine = [c for c in four if c.task == task]
        hard = {"oracle", "near_inside", "near_outside"}
        assert hard <= {c.kind for c in mine} and len(mine) == 4  # one of each stratum
        assert sum(c.label for c in mine) == 2 and [c.kind for c in mine if c.kind not in hard][0] in kinds
    assert [c.key for c in four if c.task == "c"] == ["c/1/oracle", "c/1/displaced"]
    assert stratified(cases, 4) == four and four == [c for c in cases if c in four]  # deterministic, set order
    eight = [c for c in stratified(cases, 8) if c.task == "a"]
    negatives = [c.kind for c in eight if not c.label and c.kind != "near_outside"]
    assert len(negatives) == 2 and len(set(negatives)) == 2  # the negatives alternate their kinds
    assert len({c.seed for c in eight if c.kind == "oracle"}) == 2
    with pytest.raises(ValueError, match="--per-task must be >= 1"):
        stratified(cases, 0)


def test_judge_per_task_judges_that_subset(tmp_path: Path) -> None:
    rc, s, judged = judge(tmp_path, "--reporter", "predicate", "--per-task", "3")
    assert rc == 0 and s["per_task"] == 3
    for task in TASKS.split(","):
        mine = [r for r in judged if r["task"] == task]
        assert len(mine) == 3 and [r["kind"] for r in mine][0] == "oracle", mine
        assert any(not r["label"] for r in mine)
    cases = [json.loads(line) for line in (tmp_path / "out" / "cases.jsonl").read_text().splitlines()]
    assert [c["case"] for c in cases] == [r["case"] for r in judged]


def test_an_answer_that_repeats_the_prompts_example_is_low_confidence(server: StubLLMServer, tmp_path: Path) -> None:
    """The example block of ``prompts/reporter_checked.txt``, sent back as the answer (what the 1.5B
    model did on 22 of 39 states), is marked ``copies_example``; a reason of the model's own is not."""
    template = (ROOT / "prompts" / "reporter_checked.txt").read_text()
    example = re.findall(r"```python\n(.*?)```", template, re.S)[-1]
    assert "reason = " in example

    def answer(request: dict[str, Any]) -> str:
        if "put-block" in json.dumps(request) or "bowl" in prompt_text(request).split("Goal: ")[-1]:
            return code(example)
        return code("judge = False\nreason = 'the two top blocks have the same colour'\n"
                    "wrong = ['movable small red block with obj_id 3']")

    server.respond_with(answer)
    rc, s, judged = judge(tmp_path, "--reporter", "text", "--reporter-prompt", "checked", "--model", "openai/stub",
                          "--api-base", server.base_url, "--llm-timeout", "10", "--kinds", "oracle")
    assert rc == 0 and len(judged) == 2
    by_task = {r["task"]: r for r in judged}
    assert by_task["put-block-into-matching-bowl"]["low_confidence"] == "copies_example"
    assert by_task["stack-blocks-with-alternate-color"]["low_confidence"] != "copies_example"
