"""The ``records`` reporter prompt (issue #26 item 3): capmj binds the measured facts as Python
records, the model's checking code runs over them in the sandbox.

The records are checked on real settled MuJoCo states of the judge set; the reporter's answers come
from the scripted local HTTP server (tests/llm_stub_server.py): fixtures that read the prompt, not
results.
"""

from __future__ import annotations

import ast
import json
import re
from pathlib import Path
from typing import Any

import pytest
from llm_stub_server import StubLLMServer, prompt_text

from capmj.agents.choices import REPORTER_PROMPTS
from capmj.agents.prompt_files import load_prompt
from capmj.agents.report.registry import make_reporter
from capmj.agents.report.records import PROMPT, REPAIR_TEMPERATURE, RecordsReporter
from capmj.agents.report.scene_facts import area_of
from capmj.agents.report.scene_records import RECORD_KEYS, records, records_text
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


def test_the_prompt_documents_every_record_key_and_stops_before_another_example() -> None:
    prompt = load_prompt(PROMPT)
    documented = re.findall(r'^#\s+"(\w+)"', prompt.render(""), re.M)
    documented += re.findall(r';\s+"(\w+)":', prompt.render(""))
    assert sorted(documented) == sorted(RECORD_KEYS)
    assert "\n\n# example goal" in prompt.stop
    assert REPORTER_PROMPTS == ("thesis", "checked", "records", "goalcheck", "relations")
    assert isinstance(make_reporter("text", None, "records"), RecordsReporter)


MATCHING_BOWL_CHECK = """
blocks = [o for o in objects if o["kind"] == "block"]
wrong = [b["name"] for b in blocks if b["color"] != b["inside_color"]]
judge = len(wrong) == 0
reason = "blocks outside a bowl of their colour: " + ", ".join(wrong)
"""


def judge(tmp_path: Path, server: StubLLMServer, *extra: str) -> tuple[int, dict[str, Any], list[dict[str, Any]]]:
    out = tmp_path / "out"
    rc = main(["judge", "--tasks", BOWLS, "--seeds", str(SEED), "--out", str(out), "--no-progress", "--reporter",
               "text", "--reporter-prompt", "records", "--model", "openai/stub", "--api-base", server.base_url,
               "--llm-timeout", "10", *extra])
    if rc != 0:
        return rc, {}, []
    return (rc, json.loads((out / "summary.json").read_text()),
            [json.loads(line) for line in (out / "judged.jsonl").read_text().splitlines()])


def test_checking_code_over_the_records_runs_in_the_sandbox_and_gives_the_verdict(server: StubLLMServer,
                                                                                 tmp_path: Path) -> None:
    """A correct check of this task's goal, written once against the documented keys, agrees with
    the task predicate on every state of the set, and names exactly the blocks the state breaks."""
    prompts: list[str] = []

    def answer(request: dict[str, Any]) -> str:
        text = prompt_text(request)
        assert "objects = [\n    {'name': " in text and "# goal: Put the blocks in the bowls" in text
        prompts.append(text)
        return code(MATCHING_BOWL_CHECK)

    server.respond_with(answer)
    rc, s, judged = judge(tmp_path, server, "--kinds", "oracle,displaced,wrong_bowl,near_inside,near_outside")
    assert rc == 0 and s["reporter_prompt"] == "records" and len(judged) >= 4
    assert len(prompts) == len(judged)  # one request per state
    for r in judged:
        assert r["source"] == "code" and r["verdict"] == r["label"], r
        assert (r["wrong"] == []) == r["label"] and r["confidence"] == "high", r
    assert s["overall"]["balanced_accuracy"] == 1.0
    assert any(not r["label"] for r in judged)


def test_failing_or_hostile_code_gets_one_repair_then_the_checked_question(server: StubLLMServer,
                                                                           tmp_path: Path) -> None:
    """Two failed checks: the ``checked`` question (facts, a literal answer) gives the verdict, as ``direct``."""
    answers = iter([code("import os\njudge = os.system('true') == 0"), code("judge = objects[99]['tilted']"),
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
    assert "The checking code above failed" in repair and "inside_color" in repair
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


def test_start_area_is_the_quarter_an_object_began_in(server: StubLLMServer, tmp_path: Path) -> None:
    """The reporter sees where each object started (the judged state is placed after ``start``)."""
    stage, cases = cases_of(BOWLS, ("oracle",))
    spawn = {o.name: o.pos for o in stage.scene.objects}
    seen: list[dict[str, Any]] = []

    def answer(request: dict[str, Any]) -> str:
        text = prompt_text(request)
        listing = text[text.rindex("objects = ["):text.rindex("\n# goal:")]
        seen.extend(ast.literal_eval(listing.removeprefix("objects = ")))
        return code("judge = True\nreason = 'ok'\nwrong = []")

    server.respond_with(answer)
    assert judge(tmp_path, server, "--kinds", "oracle")[0] == 0
    moved = [r for r in seen if r["kind"] == "block" and r["start_area"] != r["area"]]
    assert all(r["start_area"] == area_of(spawn[r["name"]]) for r in seen)
    assert moved  # the oracle carried at least one block to another quarter: start and end differ


def test_the_records_reporter_is_a_text_prompt(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["judge", "--tasks", BOWLS, "--seeds", str(SEED), "--out", str(tmp_path), "--reporter", "vlm",
                 "--model", "m", "--reporter-prompt", "records"]) == 2
    assert "--reporter-prompt records needs --reporter text" in capsys.readouterr().err
