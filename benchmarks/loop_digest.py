"""The LLM agent's closed loop on scripted episodes, digested: for checking that a loop change leaves
the default (``thesis``) loop exactly as it was.

Runs a fixed set of scenarios (a wrong then a right plan, a plan that acts then raises, unknown
verdicts, re-plans identical to the failed plan, no reporter) through the real local HTTP stub
server of ``tests/llm_stub_server.py`` (scripted completions: fixtures, not results) and real
MuJoCo, and prints one JSON line per episode: the episode result without timings, a SHA-256 of
every request the agent sent (messages, temperatures, seeds, in order) and of the final physics
state.  Keys that did not exist before issue #26's loop policies (``loop_policy``,
``reporter_prompt``, and per attempt ``rule``, ``confidence``, ``low_confidence``) are left out, so
the lines of older code compare.  Each version runs its own copy of this script (the agent is
built from ``LLMConfig`` + ``LLMAgentOptions`` since issue #28; before that, from 22 keywords):

    git worktree add /tmp/old <old> && (cd /tmp/old && PYTHONPATH=src:task_plugins python benchmarks/loop_digest.py) > before.jsonl
    PYTHONPATH=src:task_plugins python benchmarks/loop_digest.py > after.jsonl
    diff before.jsonl after.jsonl        # identical lines: the same requests, states and records

``--loop-policy careful`` runs the same scenarios under that policy (on code that has it).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from llm_stub_server import StubLLMServer, prompt_text  # noqa: E402

from capmj.agents.llm_agent.agent import LLMAgent  # noqa: E402
from capmj.agents.llm_agent.options import LLMAgentOptions  # noqa: E402
from capmj.llm import LLMConfig  # noqa: E402
from capmj.runner import run_episode  # noqa: E402
from capmj.tasks.registry import get_task  # noqa: E402

TASK, SEEDS = "stack-all-blocks-on-a-zone", (10001, 10003)
BLOCKS = "[n for n in get_obj_names() if ' block ' in n]"
ZONE = "[n for n in get_obj_names() if ' zone ' in n][0]"
ALL = f"for block in {BLOCKS}:\n    put_first_on_second(block, {ZONE})"
WRONG = f"for block in {BLOCKS}[:2]:\n    put_first_on_second(block, {ZONE})"
CHECK = f"""
inside = [b for b in blocks if in_zone(b, {ZONE})]
judge = len(inside) == len(blocks)
reason = f'{{len(inside)}} of {{len(blocks)}} blocks in the zone'
wrong = [b for b in blocks if b not in inside]
"""
SCENARIOS: dict[str, dict[str, Any]] = {
    "wrong_then_right": {"plans": [WRONG, ALL], "check": CHECK, "reporter": "text", "attempts": 3},
    "acts_then_raises": {"plans": [ALL + "\ncopied = [][0]", "say('done')"], "check": CHECK, "reporter": "text",
                         "attempts": 2},
    "unknown_verdicts": {"plans": [WRONG, ALL], "check": None, "reporter": "text", "attempts": 2},
    "identical_replans": {"plans": [WRONG], "check": CHECK, "reporter": "text", "attempts": 3, "replan_retries": 1},
    "no_reporter_error": {"plans": ["copied = [][0]", ALL], "check": None, "reporter": "none", "attempts": 2},
}
NEW_KEYS = ("loop_policy", "reporter_prompt")
NEW_ATTEMPT_KEYS = ("rule", "confidence", "low_confidence")


def _code(text: str) -> str:
    return f"```python\n{text.strip()}\n```"


def _responder(plans: list[str], check: str | None):
    answers = list(plans)

    def answer(request: dict[str, Any]) -> str:
        text = prompt_text(request)
        if "Write the plan for the goal in the last comment" in text:
            return _code(answers.pop(0) if len(answers) > 1 else answers[0])
        if "Judge whether the goal in the last comment" in text and check is not None:
            return _code(check)
        return "no verdict here"  # reporter without a script, its repair and direct question: unknown

    return answer


def _state_digest(world: Any) -> str:
    d, m = world.data, world.model
    h = hashlib.sha256()
    for a in (d.qpos, d.qvel, d.act, np.array([d.time]), m.eq_data, d.eq_active):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


class _Capture:
    def __init__(self, agent: LLMAgent) -> None:
        self.agent, self.name, self.model, self.world = agent, agent.name, agent.model, None

    def act(self, ctx: Any) -> None:
        self.world = ctx.world
        self.agent.act(ctx)


def _plain(result: dict[str, Any]) -> dict[str, Any]:
    for key in ("wall_s", "calls"):
        result.pop(key, None)
    llm = result.get("llm") or {}
    for key in (*NEW_KEYS, "latency_s"):
        llm.pop(key, None)
    for a in llm.get("attempts", ()):
        for key in NEW_ATTEMPT_KEYS:
            a.pop(key, None)
    return result


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--loop-policy", default=None, help="LLMAgentOptions(loop_policy=...); default: its default")
    args = ap.parse_args(argv)
    os.environ.pop("CAPMJ_LLM_CACHE", None)
    extra = {} if args.loop_policy is None else {"loop_policy": args.loop_policy}
    with StubLLMServer() as server:
        for name, sc in SCENARIOS.items():
            for seed in SEEDS:
                server.reset()
                server.respond_with(_responder(sc["plans"], sc["check"]))
                agent = LLMAgent(LLMConfig("openai/stub", api_base=server.base_url, backoff_s=0.0, timeout_s=10.0),
                                 LLMAgentOptions(reporter=sc["reporter"], attempts=sc["attempts"],
                                                 replan_retries=sc.get("replan_retries", 3), **extra))
                cap = _Capture(agent)
                res = _plain(run_episode(get_task(TASK), seed, cap).to_dict())
                requests = json.dumps(server.requests, sort_keys=True)
                res.update(scenario=name, requests=len(server.requests),
                           requests_sha256=hashlib.sha256(requests.encode()).hexdigest(),
                           state_sha256=_state_digest(cap.world) if cap.world is not None else None)
                print(json.dumps(res, sort_keys=True), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
