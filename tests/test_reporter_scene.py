"""The measured scene the reporters judge (:mod:`capmj.agents.report.scene`) and the ``relations``
reporter's repair and fallback: records on real settled MuJoCo states of the judge set; answers from
the scripted local HTTP server (tests/llm_stub_server.py): fixtures that read the prompt, not results.
"""

from __future__ import annotations

import ast
import json
from pathlib import Path
from typing import Any

from llm_stub_server import StubLLMServer, prompt_text

from capmj.agents.prompt_files import load_prompt
from capmj.agents.report.relations.reporter import PROMPT, REPAIR_TEMPERATURE
from capmj.agents.report.scene import area_of, records, records_text, start_areas_of
from capmj.bench.cli import main
from capmj.judge.cases import JudgeCase, Stage
from capmj.judge.judgeset import build_cases
from capmj.tasks.registry import get_task

SEED = 10001
BOWLS = "put-block-into-matching-bowl"
STACK = "stack-all-blocks-on-a-zone"
PYRAMID = "build-rectangular-pyramid"


def code(text: str) -> str:
    return f"```python\n{text.strip()}\n```"


def cases_of(task_name: str, kinds: tuple[str, ...]) -> tuple[Stage, dict[str, JudgeCase]]:
    task = get_task(task_name)
    return Stage(task, SEED), {c.kind: c for c in build_cases(task, SEED, kinds=kinds)[0]}


def test_records_of_real_states_follow_the_tasks_rules() -> None:
    stage, cases = cases_of(BOWLS, ("oracle", "displaced"))
    solved = records(stage.realise(cases["oracle"].poses()))
    in_bowls = [r for r in solved if r["kind"] == "block" and r["inside"]]
    assert in_bowls
    for r in in_bowls:  # the oracle's blocks sit in the bowl of their colour, and the bowl says it holds them
        bowl = next(b for b in solved if b["name"] == r["inside"])
        assert r["inside_color"] == r["color"] == bowl["color"] and r["rests_on"] == bowl["name"]
        assert r["level"] == 1 and not r["tilted"] and r["name"] in bowl["holds"]
    moved = records(stage.realise(cases["displaced"].poses()))
    out = [m for m, s in zip(moved, solved) if m["inside"] != s["inside"]]
    assert len(out) == 1 and out[0]["inside"] == out[0]["inside_color"] == "" and out[0]["rests_on"] == "table"
    assert ast.literal_eval(records_text(moved).removeprefix("objects = ")) == moved  # the prompt shows them exactly
    copy_stop = "\n    {'name': "  # the prompt's stop on an answer copying the records out matches their layout
    assert copy_stop in load_prompt(PROMPT).stop and copy_stop in records_text(moved)


def test_levels_count_the_blocks_below() -> None:
    stage, cases = cases_of(STACK, ("oracle", "unstacked"))
    rows = records(stage.realise(cases["oracle"].poses()))
    tower = sorted((r for r in rows if r["kind"] == "block" and r["level"] > 1 or
                    any(u["rests_on"] == r["name"] for u in rows)), key=lambda r: r["level"])
    assert [r["level"] for r in tower] == list(range(1, len(tower) + 1)) and len(tower) >= 3
    for lower, upper in zip(tower, tower[1:]):
        assert upper["rests_on"] == lower["name"]
    flat = records(stage.realise(cases["unstacked"].poses()))
    assert max(r["level"] for r in flat) < len(tower)
    stage, cases = cases_of(PYRAMID, ("oracle",))  # 9-4-1: the upper blocks bridge four below
    rows = records(stage.realise(cases["oracle"].poses()))
    layers = sorted(r["level"] for r in rows if r["kind"] == "block" and r["inside"])
    assert layers == [1] * 9 + [2] * 4 + [3]
    top = next(r for r in rows if r["level"] == 3)
    assert len(top["below"]) == 4 and all(next(r for r in rows if r["name"] == n)["level"] == 2 for n in top["below"])


def judge(tmp_path: Path, server: StubLLMServer, *extra: str) -> tuple[int, dict[str, Any], list[dict[str, Any]]]:
    out = tmp_path / "out"
    rc = main(["judge", "--tasks", BOWLS, "--seeds", str(SEED), "--out", str(out), "--no-progress", "--reporter",
               "text", "--reporter-prompt", "relations", "--model", "openai/stub", "--api-base", server.base_url,
               "--llm-timeout", "10", *extra])
    if rc != 0:
        return rc, {}, []
    return (rc, json.loads((out / "summary.json").read_text()),
            [json.loads(line) for line in (out / "judged.jsonl").read_text().splitlines()])


def test_failing_or_hostile_code_gets_one_warm_repair_then_the_checked_question(server: StubLLMServer,
                                                                                tmp_path: Path) -> None:
    """Two failed checks: the ``checked`` question (facts, a literal answer) gives the verdict, as ``direct``."""
    answers = iter([code("import os\nrequire_on_table(blocks())"), code("require_on_table(objects[99])"),
                    code("judge = False\nreason = 'a block is out'\nwrong = []")])
    server.respond_with(lambda request: next(answers))
    rc, s, judged = judge(tmp_path, server, "--kinds", "oracle")
    assert rc == 0 and len(judged) == 1
    r = judged[0]
    assert r["verdict"] is False and r["source"] == "direct" and r["calls"] == 3 and r["reason"] == "a block is out"
    assert (r["confidence"], r["low_confidence"]) == ("low", "direct_fallback")  # not acted on by `careful`
    assert r["errors"][0].startswith("code: ") and "import" in r["errors"][0]
    assert r["errors"][1].startswith("repair: ") and "IndexError" in r["errors"][1] and len(r["errors"]) == 2
    repair = prompt_text(server.requests[1])
    assert "The checking code above failed" in repair and "Do not set judge" in repair
    assert "already defined with the records" not in repair  # the answer did not copy the records
    # at temperature 0 the 1.5B model repeated its failed answer: the repair samples warmer, seeded by the state
    first, second = server.requests[0], server.requests[1]
    assert first.get("temperature", 0) == 0 and "seed" not in first
    assert second["temperature"] == REPAIR_TEMPERATURE > 0 and isinstance(second["seed"], int)
    assert second["stop"] == list(load_prompt(PROMPT).stop) and "\n    {'name': " in second["stop"]
    direct = prompt_text(server.requests[2])
    assert "Facts after the robot acted" in direct and "objects = [" not in direct
    assert "Goal: Put the blocks in the bowls" in direct


def test_an_answer_copying_the_records_is_told_so_and_no_verdict_at_all_is_unknown(server: StubLLMServer,
                                                                                 tmp_path: Path) -> None:
    """The 1.5B model's commonest failure: ``objects = [`` cut at the copy stop.  The repair says so in
    words; when the checked question gives no verdict either (twice), the verdict is unknown."""
    answers = iter(["objects = [", "```python\nobjects = [", "no idea", "still no idea"])
    server.respond_with(lambda request: next(answers))
    rc, s, judged = judge(tmp_path, server, "--kinds", "oracle")
    assert rc == 0 and len(judged) == 1
    r = judged[0]
    assert r["verdict"] is None and r["source"] == "unknown" and r["calls"] == 4
    assert [e.split(":")[0] for e in r["errors"]] == ["code", "repair", "direct code", "direct repair"]
    assert "SyntaxError" in r["errors"][0] and r["low_confidence"] == "no_verdict"
    assert "`objects` is already defined with the records above" in prompt_text(server.requests[1])
    assert s["overall"]["verdict_rate"] == 0.0


def test_start_area_is_the_quarter_an_object_began_in() -> None:
    """A record's ``start_area`` is the quarter its object spawned in (what the reporter's ``start`` keeps)."""
    stage, cases = cases_of(BOWLS, ("oracle",))
    spawn = {o.obj_id: o.pos for o in stage.scene.objects}
    rows = records(stage.realise(cases["oracle"].poses()), start_areas_of(spawn))
    ids = {o.name: o.obj_id for o in stage.scene.objects}
    assert all(r["start_area"] == area_of(spawn[ids[r["name"]]]) for r in rows)
    assert any(r["kind"] == "block" and r["start_area"] != r["area"] for r in rows)  # the oracle moved a block across
