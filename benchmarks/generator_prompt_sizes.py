"""Tokens of every turn of one generator conversation (gpt-4o-mini tokenizer via litellm, offline), as JSON.

Drives :func:`capmj.generate.candidate.run_candidate` for two bottom-up candidates through all
their turns — propose, pick examples, write, repair, reflect — with scripted answers (a proposal,
two picks, a module that fails a static check, then a good module from
``tests/generator_candidates``), so the prompts counted are exactly the ones a real model would
be sent, on today's installed library.  Per turn: the whole prompt (``prompt_tokens``), what the
turn added to its conversation (``new_tokens``) and what a server with a prefix cache must
actually read (``read_tokens``: the prompt after its longest common prefix with any earlier
request, as llama.cpp's slots and OpenAI's prompt caching reuse it).  A small local model reads
~20-50 prompt tokens/s on 2 cores, so ``read_tokens`` is the figure that costs minutes.

    LITELLM_LOCAL_MODEL_COST_MAP=True python benchmarks/generator_prompt_sizes.py

The real server counts with its own tokenizer (Qwen2.5: the pick-examples turn that counts 6 048
here was 6 269 at llama.cpp), so these are comparable with each other, not with a server log.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")

MODEL = "gpt-4o-mini"
ROOT = Path(__file__).resolve().parents[1]
GOOD = ROOT / "tests" / "generator_candidates" / "good_stack_in_zone.py"
BROKEN = ROOT / "tests" / "generator_candidates" / "broken_np_random.py"
PROPOSAL = {"name": "stack-small-on-big-in-zone", "goal": "Stack the small {color} block on the big block in the zone.",
            "objects": ["one big block", "one small block", "one zone"], "why": "size-ordered stacking"}


@dataclass(frozen=True)
class _Answer:
    text: str
    prompt_tokens: int
    completion_tokens: int
    cost_usd: float = 0.0
    cached: bool = False
    attempts: int = 1
    model: str = "scripted"


class _CountingClient:
    """Answers each purpose from a script and counts the tokens of what it was sent."""

    def __init__(self, answers: dict[str, str]) -> None:
        import litellm

        self._count = lambda messages: litellm.token_counter(model=MODEL, messages=messages)
        self._tokens = lambda text: litellm.token_counter(model=MODEL, text=text) if text else 0
        self.answers = answers
        self.turns: list[dict] = []
        self._seen: list[str] = []

    def complete(self, messages: list[dict], purpose: str = "", **_: object) -> _Answer:
        total = self._count(messages)
        new = self._count(messages[-1:])
        flat = "".join(f"<{m['role']}>{m['content']}" for m in messages)
        common = max((len(os.path.commonprefix([flat, s])) for s in self._seen), default=0)
        self._seen.append(flat)
        text = self.answers[purpose]
        out = self._count([{"role": "assistant", "content": text}])
        self.turns.append({"purpose": purpose, "prompt_tokens": total, "new_tokens": new,
                           "read_tokens": self._tokens(flat[common:]), "prompt_chars": len(flat)})
        return _Answer(text, total, out)


def main() -> dict:
    from capmj.generate.candidate import Context, run_candidate
    from capmj.generate.config import GenerateConfig
    from capmj.generate.library import load_library

    good, broken = GOOD.read_text(encoding="utf-8"), BROKEN.read_text(encoding="utf-8")
    client = _CountingClient({
        "generate.propose": json.dumps(PROPOSAL),
        "generate.pick_examples": '["stack-all-blocks-on-a-zone", "stack-blocks-of-same-size"]',
        "generate.write": f"```python\n{broken}\n```",
        "generate.repair": f"```python\n{good}\n```",
        "generate.reflect": '{"vote": "accept", "reason": "scripted"}',
    })
    with tempfile.TemporaryDirectory() as tmp:
        cfg = GenerateConfig(mode="bottom-up", model="scripted", out=Path(tmp), n=2, seeds=2)
        ctx = Context(cfg, client, load_library(), Path(tmp))  # type: ignore[arg-type]
        stages = [run_candidate(ctx, i).stage for i in range(cfg.n)]
    half = len(client.turns) // 2
    per = [client.turns[:half], client.turns[half:]]
    return {"model": MODEL, "tokenizer": "litellm.token_counter", "stages_reached": stages, "turns": client.turns,
            "max_prompt_tokens": max(t["prompt_tokens"] for t in client.turns),
            "read_tokens_first_candidate": sum(t["read_tokens"] for t in per[0]),
            "read_tokens_next_candidate": sum(t["read_tokens"] for t in per[1])}


if __name__ == "__main__":
    json.dump(main(), sys.stdout, indent=2)
    sys.stdout.write("\n")
