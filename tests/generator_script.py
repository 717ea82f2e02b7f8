"""Scripted LLM answers for the task generator's tests and benchmark (fixtures, never results).

Every hand-written candidate module lives in ``tests/generator_candidates/`` with a first line
``# expect: accepted | static:<check> | runtime:<check>`` (the stage and check that must reject it)
and a ``# goal:`` line.  :class:`GeneratorScript` is a responder for ``tests/llm_stub_server.py``:
it recognises which generator prompt a request carries and which candidate the conversation is
about, and answers that candidate's proposal, example picks, module, repair and vote.  Each
candidate's task name is its file stem in kebab case (the code's ``name = ...`` is rewritten to
it), so many candidates can share one run.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from llm_stub_server import prompt_text

CANDIDATES = Path(__file__).resolve().parent / "generator_candidates"
EXAMPLE_PICKS = ["stack-all-blocks-on-a-zone", "put-block-into-matching-bowl"]


@dataclass(frozen=True)
class ScriptedCandidate:
    file: str
    name: str
    goal: str
    expect: str
    code: str
    repair: str

    @property
    def expect_stage(self) -> str:
        return self.expect.split(":")[0]

    @property
    def expect_check(self) -> str | None:
        return self.expect.split(":")[1] if ":" in self.expect else None


def _named(code: str, name: str) -> str:
    return re.sub(r'^(    name = )"[^"]*"', rf'\1"{name}"', code, count=1, flags=re.M)


def candidate(file: str, *, repair: str | None = None, name: str | None = None) -> ScriptedCandidate:
    """The candidate of ``file``; ``repair`` names the file answered in the repair round
    (default: the same code again, i.e. the repair does not help)."""
    text = (CANDIDATES / file).read_text()
    expect = re.search(r"^# expect: (\S+)", text, re.M).group(1)  # type: ignore[union-attr]
    goal = re.search(r"^# goal: (.+)$", text, re.M).group(1)  # type: ignore[union-attr]
    name = name or Path(file).stem.replace("_", "-")
    fixed = (CANDIDATES / repair).read_text() if repair else text
    return ScriptedCandidate(file, name, goal, expect, _named(text, name), _named(fixed, name))


def all_candidates() -> list[ScriptedCandidate]:
    return [candidate(p.name) for p in sorted(CANDIDATES.glob("*.py"))]


class GeneratorScript:
    """Stub-server responder answering the generator's prompts for ``candidates`` (by index in
    bottom-up mode, by the task name found in the conversation afterwards)."""

    def __init__(self, candidates: list[ScriptedCandidate], vote: str = "accept") -> None:
        self.candidates = candidates
        self.vote = vote

    def _about(self, request: dict[str, Any]) -> ScriptedCandidate:
        text = prompt_text(request)
        for c in self.candidates:
            if f'"name": "{c.name}"' in text or f"  name: {c.name}\n" in text:  # proposal JSON or pick.txt
                return c
        raise AssertionError(f"no scripted candidate in conversation: {text[:300]!r}")

    def __call__(self, request: dict[str, Any]) -> str:
        last = str(request["messages"][-1]["content"])
        if "Propose one NEW task" in last:
            c = self.candidates[int(re.search(r"proposal (\d+) of", last).group(1)) - 1]  # type: ignore[union-attr]
            return json.dumps({"name": c.name, "goal": c.goal, "objects": ["blocks", "zones"], "why": "scripted"})
        c = self._about(request)
        if "Pick the 2 existing tasks" in last:
            return json.dumps(EXAMPLE_PICKS)
        if "Now write the complete module" in last:
            return f"Here is the module.\n```python\n{c.code}```\n"
        if "was rejected by the check" in last:
            return f"```python\n{c.repair}```"
        if "Vote." in last:
            return json.dumps({"vote": self.vote, "reason": "scripted vote"})
        raise AssertionError(f"unrecognised generator prompt: {last[:200]!r}")
