"""Helpers to execute the few-shot examples of the prompt files against real scenes.

Used by ``test_prompts.py`` (every example must run and succeed) and ``test_llm_chain.py``
(stub-server responders answer helper-LMP questions with the matching example's code).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.base import EpisodeContext
from capmj.agents.lmp.session import LMPSession
from capmj.agents.prompt_files import Example, PromptFile, load_prompt
from capmj.sim.objects import ObjectSpec, resting_z
from capmj.sim.world import World
from capmj.tasks.protocol import Scene
from capmj.tasks.registry import get_task

HELPER_LMPS = ("parse_obj_name", "parse_position", "parse_question", "parse_function", "parse_completion")
ALL_LMPS = ("planner", "planner_low") + HELPER_LMPS


def scene_specs(example: Example) -> tuple[ObjectSpec, ...]:
    """Object specs of an example's ``#@ scene:`` (obj_ids 1, 2, ... in list order)."""
    scene = example.json("scene")
    if not isinstance(scene, dict) or "objects" not in scene:
        raise AssertionError(f"example {example.id!r} has no '#@ scene: {{\"objects\": ...}}'")
    specs = []
    for i, entry in enumerate(scene["objects"], start=1):
        kind, color, x, y, *rest = entry
        size = rest[0] if rest and rest[0] else ("small" if kind == "block" else None)
        z = rest[1] if len(rest) > 1 and rest[1] is not None else resting_z(kind, size)
        yaw = float(rest[2]) if len(rest) > 2 else 0.0
        specs.append(ObjectSpec(i, kind, color, (float(x), float(y), float(z)), yaw=yaw, size=size))
    return tuple(specs)


def query_of(example: Example) -> tuple[str, str]:
    """(query comment line, code after it) of an example body."""
    lines = example.body.splitlines()
    for i, line in enumerate(lines):
        if line.startswith("# "):
            return line, "\n".join(lines[i + 1:]).strip("\n") + "\n"
    raise AssertionError(f"example {example.id!r} has no query comment")


def objects_line(example: Example) -> str | None:
    for line in example.body.splitlines():
        if line.startswith("objects = "):
            return line
    return None


class _PlainTask:
    name = "prompt-example"
    tags = frozenset()

    def evaluate(self, scene, state):  # noqa: ANN001, ANN201 - never used for judging
        raise AssertionError("no task predicate for this example")


def build_context(example: Example, seed: int = 0) -> EpisodeContext:
    """A settled world for the example's scene, in an episode context (task when named)."""
    specs = scene_specs(example)
    task_name = example.meta.get("task")
    task = get_task(task_name) if task_name else _PlainTask()
    info = example.json("info", {})
    query, _ = query_of(example)
    scene = Scene(specs, query[2:].strip(), info)
    world = World(specs)
    world.settle()
    return EpisodeContext(task, seed, scene, world)


@dataclass
class ExampleLLM:
    """A fake ``complete`` for LMPSession: answers a helper question with the code of the example
    (of the prompt that was rendered) whose query line equals the question's last comment line.
    The prompts and the code are the real files; nothing is invented here."""

    prompts: Mapping[str, PromptFile] = field(default_factory=lambda: {n: load_prompt(n) for n in ALL_LMPS})
    asked: list[tuple[str, str]] = field(default_factory=list)
    stops: list[tuple[str, ...]] = field(default_factory=list)
    """The stop sequences each call was sent with."""
    drop_first_code_line: bool = False
    """Answer without the example's first code line (as a small model copying it did)."""

    def answer(self, user_text: str) -> tuple[str, str]:
        """(lmp, answer text) for a rendered prompt."""
        for name, prompt in self.prompts.items():
            head = prompt.template.split("<<QUESTION>>")[0]
            if user_text.startswith(head):
                question = user_text[len(head):]
                query = [ln for ln in question.splitlines() if ln.startswith("# ")][-1].strip()
                for ex in prompt.examples:
                    q, code = query_of(ex)
                    if q.strip() == query:
                        if self.drop_first_code_line:
                            lines = code.splitlines(keepends=True)
                            first = next(i for i, ln in enumerate(lines) if ln.strip() and not ln.startswith("#"))
                            code = "".join(lines[:first] + lines[first + 1:])
                        return name, f"```python\n{code}```"
                raise AssertionError(f"no {name} example answers {query!r}")
        raise AssertionError(f"unknown prompt: {user_text[:200]!r}")

    def __call__(self, messages: Sequence[Mapping[str, Any]], purpose: str = "", stop: Sequence[str] = ()) -> Any:
        self.stops.append(tuple(stop))
        user = messages[-1]["content"]
        lmp, text = self.answer(user)
        self.asked.append((lmp, user))
        return SimpleNamespace(text=text, cached=False)


def session_for(ctx: EpisodeContext, llm: ExampleLLM | None = None) -> tuple[LMPSession, PlannerAPI]:
    api = PlannerAPI(ctx)
    session = LMPSession(complete=llm or ExampleLLM(), api=api.functions(), objects_text=api.objects_text)
    return session, api


def examples(lmp: str) -> list[tuple[str, Example]]:
    return [(lmp, ex) for ex in load_prompt(lmp).examples]


def dumps(value: Any) -> str:
    return json.dumps(value, default=str)
