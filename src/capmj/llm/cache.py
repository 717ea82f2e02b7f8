"""On-disk cache of LLM completions, keyed by everything that determines the answer.

Why: benchmark runs are repeated (debugging a task, re-scoring, CI) and a temperature-0 answer to
the same request is worth reusing instead of paying for it again.  The key covers model, api_base,
the full messages (images included), temperature, max_tokens, the sampling seed and the stop
sequences and the offered tools (each only when sent: requests without them keep the keys they had
before they were sent), but never the API
key: rotating a key must not invalidate the cache, and secrets must not be derivable from file
names.

Layout: ``<root>/<key[:2]>/<key[2:4]>/<key>.json`` (two-level fan-out keeps directories small).
Files are written atomically (:func:`capmj.atomic.atomic_write`) so a crash or a parallel run never
leaves a half-written entry; an unreadable or malformed entry is simply a miss and is overwritten.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from capmj.atomic import atomic_write
from capmj.errors import ConfigError

__all__ = ["CACHE_ENV", "CACHE_FORMAT", "CompletionCache", "cache_key", "env_cache_dir"]

CACHE_FORMAT = 1
"""Bumped whenever the stored record layout changes; older entries then read as misses."""

CACHE_ENV = "CAPMJ_LLM_CACHE"
"""The cache folder of LLM completions for commands not given one (the bench, the generator):
an environment variable, so it reaches every worker process."""


def env_cache_dir() -> Path | None:
    """The cache folder ``$CAPMJ_LLM_CACHE`` names, or None."""
    value = os.environ.get(CACHE_ENV, "").strip()
    return Path(value) if value else None

_log = logging.getLogger(__name__)

# Fields every stored record must carry, with their accepted types.
_FIELDS: dict[str, type | tuple[type, ...]] = {
    "text": str,
    "model": str,
    "prompt_tokens": int,
    "completion_tokens": int,
    "cost_usd": (int, float),
    "latency_s": (int, float),
}


def cache_key(
    *,
    model: str,
    api_base: str | None,
    messages: Sequence[Mapping[str, Any]],
    temperature: float,
    max_tokens: int,
    seed: int | None = None,
    stop: Sequence[str] = (),
    tools: Sequence[Mapping[str, Any]] | None = None,
) -> str:
    """sha256 hex digest of the canonical JSON of the request's answer-determining fields."""
    payload: dict[str, Any] = {
        "format": CACHE_FORMAT,
        "model": model,
        "api_base": api_base,
        "messages": list(messages),
        "temperature": float(temperature),
        "max_tokens": int(max_tokens),
    }
    if seed is not None:
        payload["seed"] = int(seed)
    if stop:  # absent when none is sent: requests without stops keep their keys
        payload["stop"] = list(stop)
    if tools:  # likewise: requests without tools keep their keys
        payload["tools"] = list(tools)
    try:
        canonical = json.dumps(
            payload, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False
        )
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"LLM messages must be JSON-serialisable to be cached: {exc}") from exc
    return hashlib.sha256(canonical.encode("utf-8")).hexdigest()


def _valid(record: object, key: str) -> bool:
    if not isinstance(record, dict) or record.get("format") != CACHE_FORMAT:
        return False
    if record.get("key") != key:
        return False
    for name, kind in _FIELDS.items():
        value = record.get(name)
        if isinstance(value, bool) or not isinstance(value, kind):
            return False
        if isinstance(value, float) and not math.isfinite(value):
            return False
    calls = record.get("tool_calls", [])  # [[id, name, arguments], ...], only for answers with calls
    return isinstance(calls, list) and all(
        isinstance(c, list) and len(c) == 3 and all(isinstance(x, str) for x in c) for c in calls)


class CompletionCache:
    """One JSON file per request key under ``root``; safe to share between processes."""

    def __init__(self, root: Path | str) -> None:
        self.root = Path(root)

    def path_for(self, key: str) -> Path:
        if len(key) < 8 or not all(c in "0123456789abcdef" for c in key):
            raise ValueError(f"not a cache key: {key!r}")
        return self.root / key[:2] / key[2:4] / f"{key}.json"

    def get(self, key: str) -> dict[str, Any] | None:
        """The stored record, or None on a miss (absent, unreadable, corrupt, other format)."""
        path = self.path_for(key)
        try:
            record = json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return None
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            _log.warning("ignoring unreadable LLM cache entry %s: %s", path, exc)
            return None
        if not _valid(record, key):
            _log.warning("ignoring malformed LLM cache entry %s", path)
            return None
        return record

    def put(self, key: str, record: Mapping[str, Any]) -> Path:
        """Store ``record`` (plus key and format) atomically; returns the entry's path."""
        path = self.path_for(key)
        data = {**record, "key": key, "format": CACHE_FORMAT}
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_write(path, "w", encoding="utf-8") as handle:
            json.dump(data, handle, ensure_ascii=False, indent=1, allow_nan=False)
        return path
