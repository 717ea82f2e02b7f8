"""The command-line options that configure an LLM client, defined once for every capmj command.

``python -m capmj.bench`` and ``python -m capmj.generate`` both talk to a model; a user who
learnt ``--llm-timeout`` on one must find it on the other, with the same meaning (issue #27).
Each option names the :class:`~capmj.llm.LLMConfig` field it sets, so a command can turn the
parsed values into configuration without copying names by hand.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import Any, Callable, Mapping

from capmj.llm.config import DEFAULT_TIMEOUT_S


@dataclass(frozen=True)
class LLMOption:
    """One flag: its spellings, its argparse ``dest``, the ``LLMConfig`` field it sets."""

    flags: tuple[str, ...]
    dest: str
    field: str
    type: Callable[[str], Any]
    metavar: str | None
    help: str


LLM_OPTIONS: tuple[LLMOption, ...] = (
    LLMOption(("--model",), "model", "model", str, None,
              "litellm model string, e.g. gpt-4o-mini or openai/<local model>"),
    LLMOption(("--api-base",), "api_base", "api_base", str, "URL", "OpenAI-compatible API base URL (a local server)"),
    LLMOption(("--temperature",), "temperature", "temperature", float, "T", "sampling temperature (default 0)"),
    LLMOption(("--llm-timeout",), "timeout_s", "timeout_s", float, "S",
              f"seconds without a streamed token before a request fails and is retried (default {DEFAULT_TIMEOUT_S:g}; "
              "raise it above the server's time to read a cold prompt)"),
    LLMOption(("--llm-max-tokens",), "llm_max_tokens", "max_tokens", int, "N",
              "completion-token limit of each request (default 2048; the generator 4096)"),
    LLMOption(("--llm-cache", "--cache-dir"), "cache_dir", "cache_dir", str, "DIR",
              "cache completions in DIR (default: $CAPMJ_LLM_CACHE); reruns replay them without HTTP"),
)
"""The shared options, in help order."""


def add_llm_options(group: Any, defaults: Mapping[str, Any] | None = None, *, model_required: bool = False) -> None:
    """Add every :data:`LLM_OPTIONS` flag to ``group`` (a parser or an argument group).

    ``defaults`` maps ``LLMConfig`` field names to defaults; absent fields default to ``None``
    (the command resolves them later, e.g. from an earlier run's ``config.json``)."""
    for o in LLM_OPTIONS:
        kw: dict[str, Any] = {"dest": o.dest, "type": o.type, "help": o.help,
                              "default": (defaults or {}).get(o.field)}
        if o.metavar:
            kw["metavar"] = o.metavar
        if o.field == "model" and model_required:
            kw["required"] = True
        group.add_argument(*o.flags, **kw)


def llm_values(args: argparse.Namespace) -> dict[str, Any]:
    """The parsed shared options by ``LLMConfig`` field name."""
    return {o.field: getattr(args, o.dest) for o in LLM_OPTIONS}


__all__ = ["LLMOption", "LLM_OPTIONS", "add_llm_options", "llm_values"]
