"""The ``goalcheck`` reporter prompt (issue #26 item 3): the model writes the goal's check from the
goal and the objects' unchanging keys; capmj runs it on the measured final and start scenes.

States are real settled MuJoCo states of the judge set; the answers come from the scripted local
HTTP server (tests/llm_stub_server.py): fixtures that read the prompt, not results.
"""

from __future__ import annotations

import ast
import json
from pathlib import Path
from typing import Any

from llm_stub_server import StubLLMServer, prompt_text

from capmj.agents.report.registry import make_reporter
from capmj.agents.report.goalcheck import HOLDS_AT_START, GoalCheckReporter
from capmj.agents.report.scene_records import INVENTORY_KEYS
from capmj.bench.cli import main

SEED = 10001
BOWLS = "put-block-into-matching-bowl"

MATCHING_BOWL_CHECK = """
blocks = [o for o in objects if o["kind"] == "block"]
wrong = [b["name"] for b in blocks if b["color"] != b["inside_color"]]
judge = len(wrong) == 0
reason = "blocks outside a bowl of their colour: " + ", ".join(wrong)
"""
NOTHING_TILTED = "wrong = [o['name'] for o in objects if o['tilted']]\njudge = not wrong\nreason = 'tilted: ' + str(wrong)"
"""Reads a measured key, yet holds in the start scene too (nothing is tilted there)."""
NEVER_ACHIEVED = "judge = False\nreason = 'the blocks are not in their bowls'\nwrong = []"
IN_A_BOWL_WORD = ("wrong = [o['name'] for o in objects if o['kind'] == 'block' and o['inside'] != 'bowl']\n"
                  "judge = not wrong\nreason = 'not in a bowl: ' + ', '.join(wrong)")
"""Compares ``inside`` with a word no record has (the bowls' names are "... bowl with obj_id ...")."""


def code(text: str) -> str:
    return f"```python\n{text.strip()}\n```"


def judge(tmp_path: Path, server: StubLLMServer, kinds: str) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    out = tmp_path / "out"
    rc = main(["judge", "--tasks", BOWLS, "--seeds", str(SEED), "--kinds", kinds, "--out", str(out), "--no-progress",
               "--reporter", "text", "--reporter-prompt", "goalcheck", "--model", "openai/stub", "--api-base",
               server.base_url, "--llm-timeout", "10"])
    assert rc == 0
    return (json.loads((out / "summary.json").read_text()),
            [json.loads(line) for line in (out / "judged.jsonl").read_text().splitlines()])


def listing(text: str) -> list[dict[str, Any]]:
    """The ``objects = [...]`` the question shows (the last one of the prompt)."""
    return list(ast.literal_eval(text[text.rindex("objects = ["):text.rindex("\n# goal:")].removeprefix("objects = ")))


def test_the_check_sees_only_the_inventory_and_runs_on_the_measured_state(server: StubLLMServer,
                                                                           tmp_path: Path) -> None:
    """Every state of an episode gets the same question (goal + unchanging keys), and one check
    written against the documented keys agrees with the predicate on each state."""
    prompts: list[str] = []

    def answer(request: dict[str, Any]) -> str:
        prompts.append(prompt_text(request))
        return code(MATCHING_BOWL_CHECK)

    server.respond_with(answer)
    s, judged = judge(tmp_path, server, "oracle,displaced,wrong_bowl,near_outside")
    assert s["reporter_prompt"] == "goalcheck" and len(judged) >= 3 and any(not r["label"] for r in judged)
    for r in judged:
        assert (r["source"], r["verdict"], r["confidence"]) == ("code", r["label"], "high"), r
    assert len(set(prompts)) == 1  # the question does not depend on the state: a cache asks once per episode
    shown = listing(prompts[0])
    assert shown and all(tuple(row) == INVENTORY_KEYS for row in shown)
    assert '"inside_color"' in prompts[0] and "# goal: Put the blocks in the bowls" in prompts[0]  # keys documented


def test_a_check_that_holds_at_the_start_is_repaired_then_doubted(server: StubLLMServer, tmp_path: Path) -> None:
    """A check that only asks "nothing tilted?" also holds in the start scene, where no goal holds.
    The repair request says so; repeated, the verdict is kept but low-confidence (``holds_at_start``)."""
    server.respond_with(lambda request: code(NOTHING_TILTED))
    _, judged = judge(tmp_path, server, "oracle,displaced")
    assert len(server.requests) == 2 * len(judged)  # the first answer and its repair, per state
    assert HOLDS_AT_START in prompt_text(server.requests[1])
    for r in judged:
        assert (r["verdict"], r["source"], r["confidence"], r["low_confidence"]) == (True, "repair", "low",
                                                                                       "holds_at_start"), r
        assert r["errors"] == [f"code: {HOLDS_AT_START}"]
    server.respond_with(lambda request: code(MATCHING_BOWL_CHECK if HOLDS_AT_START in prompt_text(request)
                                             else NOTHING_TILTED))
    _, judged = judge(tmp_path / "repaired", server, "oracle,displaced")
    assert [(r["verdict"], r["source"], r["confidence"]) for r in judged] == [
        (r["label"], "repair", "high") for r in judged]


def test_a_check_that_fails_only_on_the_start_scene_is_not_held_against_it(server: StubLLMServer,
                                                                            tmp_path: Path) -> None:
    """The first block in a bowl does not exist at the start: the check errs there, and counts."""
    server.respond_with(lambda request: code(
        "inside = [o for o in objects if o['kind'] == 'block' and o['inside']]\nfirst = inside[0]\n" + MATCHING_BOWL_CHECK))
    _, judged = judge(tmp_path, server, "oracle")
    assert [(r["verdict"], r["source"], r["calls"], r["errors"]) for r in judged] == [(True, "code", 1, [])]


def test_a_blind_check_is_repaired_with_what_it_missed_then_doubted(server: StubLLMServer, tmp_path: Path) -> None:
    """``judge = False`` reads nothing of the scene; ``o['inside'] != 'bowl'`` compares with a value
    no record can have.  Each gets the repair request naming its fault (the second with the values
    ``inside`` really has); repeated, the verdict is kept but low-confidence (``blind_check``)."""
    for answer, needle in ((NEVER_ACHIEVED, "reads none of the measured keys"),
                           (IN_A_BOWL_WORD, "compares \"inside\" with 'bowl'")):
        server.respond_with(lambda request, a=answer: code(a))
        before = len(server.requests)
        _, judged = judge(tmp_path / needle[:6], server, "oracle,displaced")
        repair = prompt_text(server.requests[before + 1])
        assert needle in repair and len(server.requests) - before == 2 * len(judged)
        for r in judged:
            assert (r["verdict"], r["source"], r["confidence"], r["low_confidence"]) == (False, "repair", "low",
                                                                                           "blind_check"), r
            assert len(r["errors"]) == 1 and needle in r["errors"][0]
    assert "bowl with obj_id" in repair  # the values of "inside" in this scene: the bowls' full names
    server.respond_with(lambda request: code(MATCHING_BOWL_CHECK if "compares" in prompt_text(request)
                                             else IN_A_BOWL_WORD))
    _, judged = judge(tmp_path / "repaired", server, "oracle,displaced")
    assert [(r["verdict"], r["source"], r["confidence"]) for r in judged] == [
        (r["label"], "repair", "high") for r in judged]


def test_goalcheck_is_a_text_prompt() -> None:
    assert isinstance(make_reporter("text", None, "goalcheck"), GoalCheckReporter)
