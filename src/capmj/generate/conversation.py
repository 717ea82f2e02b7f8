"""One candidate's multi-turn conversation with the LLM, every message recorded.

Each turn appends the user message and the assistant's answer to one growing message list (the
LLM sees everything said so far), goes through :class:`capmj.llm.LLMClient` (retries, cache,
accounting) and is logged with its purpose, tokens, cost and whether it came from the cache.
:meth:`Conversation.save` writes the whole log as JSON; ``generation.jsonl`` points to it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from capmj.llm import LLMClient


@dataclass
class Conversation:
    """Messages of one candidate and the accounting of each call."""

    client: LLMClient
    system: str
    messages: list[dict[str, Any]] = field(default_factory=list)
    turns: list[dict[str, Any]] = field(default_factory=list)

    def __post_init__(self) -> None:
        if not self.messages:
            self.messages.append({"role": "system", "content": self.system})

    def ask(self, text: str, purpose: str) -> str:
        """Send ``text`` as the next user message; return (and record) the answer."""
        self.messages.append({"role": "user", "content": text})
        c = self.client.complete(self.messages, purpose=purpose)
        self.messages.append({"role": "assistant", "content": c.text})
        self.turns.append({"purpose": purpose, "prompt_tokens": c.prompt_tokens, "completion_tokens": c.completion_tokens,
                           "cost_usd": c.cost_usd, "cached": c.cached, "attempts": c.attempts, "model": c.model})
        return c.text

    @property
    def usage(self) -> dict[str, Any]:
        return {
            "calls": len(self.turns),
            "cached_calls": sum(t["cached"] for t in self.turns),
            "prompt_tokens": sum(t["prompt_tokens"] for t in self.turns),
            "completion_tokens": sum(t["completion_tokens"] for t in self.turns),
            "cost_usd": sum(t["cost_usd"] for t in self.turns if not t["cached"]),
        }

    def save(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps({"messages": self.messages, "turns": self.turns}, indent=1) + "\n", encoding="utf-8")


__all__ = ["Conversation"]
