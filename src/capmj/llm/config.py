"""What an LLM client is told: which model, where, how patiently, and from which cache.

Frozen, and checked when built, so a bad setting fails at the command line rather than at the
first request of a long run.  :class:`~capmj.llm.client.LLMClient` reads it; the benchmark stores
it in ``config.json``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from capmj.errors import ConfigError
from capmj.llm.keys import api_key_for

DEFAULT_TIMEOUT_S = 300.0
"""Per-request timeout.  Generous on purpose: a small local model on a few CPU cores reads a cold
planner prompt for tens of seconds before it writes (``docs/llm.md``); a cloud provider that hangs
still ends."""

LOCAL_DUMMY_KEY = "sk-local"
"""Key sent to a self-hosted ``api_base`` when none is configured (OpenAI clients demand one)."""


@dataclass(frozen=True)
class LLMConfig:
    """Which model to ask and how patiently.  ``model`` is any litellm model string."""

    model: str
    api_base: str | None = None
    api_key: str | None = field(default=None, repr=False)
    """The provider's key (None: the variable its provider reads, see :mod:`capmj.llm.keys`);
    never shown in a repr."""
    temperature: float = 0.0
    max_tokens: int = 2048
    timeout_s: float = DEFAULT_TIMEOUT_S
    max_retries: int = 3
    backoff_s: float = 1.0
    cache_dir: Path | None = None
    mock_response: str | None = None
    cache_only: bool = False
    """Answer only from ``cache_dir``: a missing entry is an LLMError, never a live call."""
    stream: bool = True
    """Stream answers, so ``timeout_s`` bounds the silence between two chunks (a stall), not the
    whole answer (:mod:`capmj.llm.stream`); a stalled answer keeps what arrived."""

    def __post_init__(self) -> None:
        if not self.model:
            raise ConfigError("LLMConfig.model must be a litellm model string, e.g. 'gpt-4o-mini'")
        if not (self.timeout_s > 0 and math.isfinite(self.timeout_s)):
            raise ConfigError(f"LLMConfig.timeout_s must be positive, got {self.timeout_s}")
        if self.max_retries < 0 or self.backoff_s < 0 or self.max_tokens <= 0:
            raise ConfigError("LLMConfig: max_retries and backoff_s must be >= 0, max_tokens > 0")
        if self.cache_dir is not None and not isinstance(self.cache_dir, Path):
            object.__setattr__(self, "cache_dir", Path(self.cache_dir))
        if self.cache_only and self.cache_dir is None:
            raise ConfigError("LLMConfig.cache_only needs cache_dir (the folder to replay from)")

    @property
    def resolved_api_key(self) -> str | None:
        """The key to send, always explicitly: ``api_key``, else a dummy for a local ``api_base``,
        else the variable the provider reads, from the secrets taken from this process's
        environment or still in it (:func:`capmj.llm.keys.api_key_for`; None when there is none)."""
        if self.api_key is not None:
            return self.api_key
        return LOCAL_DUMMY_KEY if self.api_base else api_key_for(self.model, self.api_base)
