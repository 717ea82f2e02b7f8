"""A small, retrying, caching, accounting LLM client over litellm.

Why our own retry loop instead of litellm's: the benchmark must record exactly how many attempts
each call took, back off deterministically (reproducible runs, fast tests with an injected sleep)
and turn every provider failure into one :class:`~capmj.errors.LLMError` that an episode can
record.  What the client is told is :mod:`capmj.llm.config`, what it records
:mod:`capmj.llm.records`, what it knows of litellm and the providers :mod:`capmj.llm.provider`,
and the bound on requests in flight :mod:`capmj.llm.gate`.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from capmj.errors import ConfigError, LLMError
from capmj.llm.cache import CompletionCache, cache_key
from capmj.llm.config import LLMConfig
from capmj.llm.gate import request_gate
from capmj.llm.messages import Message
from capmj.llm.provider import (
    MAX_RETRY_AFTER_S,
    cost,
    import_litellm,
    is_retryable,
    nonneg_int,
    retry_after,
    short,
    takes_seed,
    text_of,
)
from capmj.llm.records import CallRecord, Completion, ToolCall, Usage
from capmj.llm.stream import StreamCut, ToolCallParts, cut_answer, drain, tool_calls_of

# LLMConfig and takes_seed are re-exported: tests import them from here.
__all__ = ["LLMClient", "LLMConfig", "takes_seed"]

_log = logging.getLogger(__name__)


class LLMClient:
    """Sends chat requests; retries transient failures; caches; records every call.

    ``sleep`` is injectable so tests can check the back-off schedule without waiting.  Thread-safe
    for concurrent ``complete`` calls (accounting is locked; the cache writes atomically).
    """

    def __init__(self, config: LLMConfig, *, sleep: Callable[[float], None] = time.sleep) -> None:
        self.config = config
        self._sleep = sleep
        self._cache = CompletionCache(config.cache_dir) if config.cache_dir is not None else None
        self._records: list[CallRecord] = []
        self._lock = threading.Lock()

    # -- accounting -------------------------------------------------------------------------
    @property
    def records(self) -> tuple[CallRecord, ...]:
        with self._lock:
            return tuple(self._records)

    def usage(self) -> Usage:
        records = self.records
        return Usage(
            calls=len(records),
            cached_calls=sum(r.cached for r in records),
            failed_calls=sum(r.error is not None for r in records),
            prompt_tokens=sum(r.prompt_tokens for r in records),
            completion_tokens=sum(r.completion_tokens for r in records),
            cost_usd=sum(r.cost_usd for r in records if not r.cached),
            latency_s=sum(r.latency_s for r in records),
        )

    def _record(self, c: Completion | None, *, purpose: str, latency: float, attempts: int,
                error: str | None = None, partial: str | None = None) -> None:
        record = CallRecord(
            purpose=purpose,
            model=c.model if c else self.config.model,
            prompt_tokens=c.prompt_tokens if c else 0,
            completion_tokens=c.completion_tokens if c else 0,
            cost_usd=c.cost_usd if c else 0.0,
            latency_s=latency,
            cached=c.cached if c else False,
            attempts=attempts,
            error=error,
            partial=partial,
            cut=c.cut if c else None,
            tool_calls=len(c.tool_calls) if c else 0,
        )
        with self._lock:
            self._records.append(record)

    # -- the call ---------------------------------------------------------------------------
    def complete(self, messages: Sequence[Message], *, purpose: str = "",
                 mock_response: str | None = None, temperature: float | None = None,
                 seed: int | None = None, stop: Sequence[str] = (),
                 tools: Sequence[Mapping[str, Any]] | None = None) -> Completion:
        """Answer ``messages`` (OpenAI chat format), from the cache when possible.

        ``temperature`` overrides ``config.temperature`` for this call; ``seed`` asks the provider
        to sample reproducibly (the OpenAI ``seed`` parameter, honoured by OpenAI, llama.cpp,
        Ollama, vLLM; not sent to providers litellm knows do not take it).  ``stop`` sequences end
        the answer (sent to the provider, and cut here too, for one that ignores them).  ``tools``
        (OpenAI-format function tools) lets the model answer with calls (``Completion.tool_calls``,
        with or without text).  All four are part of the cache key.  ``mock_response`` (or ``config.mock_response``) makes litellm answer offline
        without any HTTP; such answers are never cached, so they cannot poison a cache used for
        real runs.  Raises :class:`LLMError` when the provider fails after all retries or answers
        no text (and no tool call).
        """
        cfg = self.config
        if not messages or not all(isinstance(m, Mapping) and "role" in m for m in messages):
            raise ConfigError("messages must be a non-empty list of {'role': ..., 'content': ...}")
        temperature = cfg.temperature if temperature is None else float(temperature)
        if not (math.isfinite(temperature) and temperature >= 0):
            raise ConfigError(f"temperature must be a finite number >= 0, got {temperature}")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
            raise ConfigError(f"seed must be an integer or None, got {seed!r}")
        stop = tuple(stop)
        if not all(isinstance(x, str) and x for x in stop) or len(stop) > 4:
            raise ConfigError(f"stop must be at most 4 non-empty strings (the OpenAI limit), got {stop!r}")
        request: list[dict[str, Any]] = [dict(m) for m in messages]  # copies: the caller's may change
        offered = [dict(t) for t in tools] if tools else None
        mock = mock_response if mock_response is not None else cfg.mock_response
        start = time.monotonic()
        key = None
        if self._cache is not None and mock is None:
            key = cache_key(model=cfg.model, api_base=cfg.api_base, messages=request,
                            temperature=temperature, max_tokens=cfg.max_tokens, seed=seed, stop=stop,
                            tools=offered)
            stored = self._cache.get(key)
            if stored is not None:
                hit = Completion(
                    text=stored["text"], model=stored["model"],
                    prompt_tokens=stored["prompt_tokens"],
                    completion_tokens=stored["completion_tokens"],
                    cost_usd=float(stored["cost_usd"]), latency_s=time.monotonic() - start,
                    cached=True, attempts=0, purpose=purpose,
                    tool_calls=tuple(ToolCall(*c) for c in stored.get("tool_calls", ())),
                )
                self._record(hit, purpose=purpose, latency=hit.latency_s, attempts=0)
                return hit
            if cfg.cache_only:
                miss = LLMError(f"cache-only: no cached completion for {purpose or 'this request'} "
                                f"(key {key[:12]}... under {cfg.cache_dir}); no live call was made. "
                                "Rerun without cache-only to ask the model.")
                self._record(None, purpose=purpose, latency=0.0, attempts=0, error=str(miss))
                raise miss
        import_litellm()  # seconds on first use; not part of the call's latency
        start = time.monotonic()
        result, calls, attempts, error = self._call_with_retries(request, mock, temperature, seed, stop, offered)
        if error is not None:
            self._record(None, purpose=purpose, latency=time.monotonic() - start,
                         attempts=attempts, error=str(error), partial=error.partial)
            raise error
        completion = self._to_completion(result, start=start, attempts=attempts, purpose=purpose, stop=stop,
                                         tool_calls=calls)
        if key is not None and self._cache is not None:
            self._store(key, completion)
        self._record(completion, purpose=purpose, latency=completion.latency_s, attempts=attempts)
        return completion

    def _call_with_retries(self, messages: list[dict[str, Any]], mock: str | None, temperature: float,
                           seed: int | None, stop: tuple[str, ...], tools: list[dict[str, Any]] | None = None,
                           ) -> tuple[Any, tuple[ToolCall, ...], int, LLMError | None]:
        """(response, tool calls, attempts, None) on success, (None, (), attempts, error) on final
        failure; a failed stream's text so far is on the error (``partial``)."""
        cfg = self.config
        litellm = import_litellm()
        kwargs: dict[str, Any] = dict(
            model=cfg.model, messages=messages, temperature=temperature,
            max_tokens=cfg.max_tokens, timeout=cfg.timeout_s, api_base=cfg.api_base,
            api_key=cfg.resolved_api_key, num_retries=0,
        )
        if seed is not None and takes_seed(cfg.model, cfg.api_base):
            kwargs["seed"] = seed
        if mock is not None:
            kwargs["mock_response"] = mock
        if stop:
            kwargs["stop"] = list(stop)
        if tools:
            kwargs["tools"] = tools
        if cfg.stream:
            kwargs.update(stream=True, stream_options={"include_usage": True})
        total = cfg.max_retries + 1
        partial: str | None = None
        for attempt in range(1, total + 1):
            gate = request_gate()
            parts = ToolCallParts()
            try:
                if gate is not None:
                    gate.acquire()
                try:
                    response = litellm.completion(**kwargs)
                    if cfg.stream:
                        response = drain(response, litellm, messages, parts)
                finally:
                    if gate is not None:
                        gate.release()
            except Exception as exc:  # every provider failure becomes LLMError below
                if isinstance(exc, StreamCut):
                    partial = exc.partial or partial
                    exc = exc.error  # noqa: PLW2901 - classify the cause, keep what arrived
                wait_s = cfg.backoff_s * 2 ** (attempt - 1)
                asked = retry_after(exc)
                if asked is not None:
                    wait_s = max(wait_s, asked)
                if attempt < total and is_retryable(exc) and wait_s <= MAX_RETRY_AFTER_S:
                    self._sleep(wait_s)
                    continue
                plural = "s" if attempt != 1 else ""
                got = f"; {len(partial)} characters had arrived" if partial else ""
                error = LLMError(f"{cfg.model}: {type(exc).__name__}: {short(exc)} "
                                 f"after {attempt} attempt{plural}{got}", partial=partial)
                error.__cause__ = exc
                return None, (), attempt, error
            calls = (parts.calls() if cfg.stream else tool_calls_of(response)) if tools else ()
            if text_of(response) is None and not calls:
                return None, (), attempt, LLMError(f"{cfg.model}: response has no text content")
            return response, calls, attempt, None
        raise AssertionError("unreachable")  # pragma: no cover

    def _to_completion(self, response: Any, *, start: float, attempts: int, purpose: str,
                       stop: tuple[str, ...] = (), tool_calls: tuple[ToolCall, ...] = ()) -> Completion:
        usage = getattr(response, "usage", None)
        model = getattr(response, "model", None)
        text, cut = cut_answer(text_of(response) or "", stop)
        return Completion(
            text=text,
            cut=cut,
            model=model if isinstance(model, str) and model else self.config.model,
            prompt_tokens=nonneg_int(getattr(usage, "prompt_tokens", 0)),
            completion_tokens=nonneg_int(getattr(usage, "completion_tokens", 0)),
            cost_usd=cost(response),
            latency_s=time.monotonic() - start,
            cached=False,
            attempts=attempts,
            purpose=purpose,
            tool_calls=tool_calls,
        )

    def _store(self, key: str, c: Completion) -> None:
        assert self._cache is not None
        record = {"text": c.text, "model": c.model, "prompt_tokens": c.prompt_tokens,
                  "completion_tokens": c.completion_tokens, "cost_usd": c.cost_usd,
                  "latency_s": c.latency_s, "created": time.time()}
        if c.tool_calls:  # absent without calls: entries stay as they were
            record["tool_calls"] = [[t.id, t.name, t.arguments] for t in c.tool_calls]
        try:
            self._cache.put(key, record)
        except OSError as exc:  # a full disk must not throw away an answer already paid for
            _log.warning("could not write LLM cache entry: %s", exc)

