"""A small, retrying, caching, accounting LLM client over litellm.

Why our own retry loop instead of litellm's: the benchmark must record exactly how many attempts
each call took, back off deterministically (reproducible runs, fast tests with an injected sleep)
and turn every provider failure into one :class:`~capmj.errors.LLMError` that an episode can
record.  litellm is imported lazily because importing it costs seconds, and with
``LITELLM_LOCAL_MODEL_COST_MAP`` set so that the import never fetches a price list from the net.
"""

from __future__ import annotations

import base64
import functools
import logging
import math
import os
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

from capmj.errors import ConfigError, LLMError
from capmj.llm.cache import CompletionCache, cache_key
from capmj.llm.stream import StreamCut, cut_answer, drain

__all__ = ["CallRecord", "Completion", "DEFAULT_TIMEOUT_S", "LLMClient", "LLMConfig", "Usage", "image_part",
           "set_request_gate", "takes_seed", "text_part"]

DEFAULT_TIMEOUT_S = 300.0
"""Per-request timeout.  Generous on purpose: a 1.5B model on 2 CPU cores needs 40-90 s for a cold
2k-token planner prompt and ~10 tokens/s of output; a cloud provider that hangs still ends."""

Message = Mapping[str, Any]

_log = logging.getLogger(__name__)

LOCAL_DUMMY_KEY = "sk-local"
"""Key sent to a self-hosted ``api_base`` when none is configured (OpenAI clients demand one)."""

# litellm exception class names that mean "try again later"; checked by name along the MRO so this
# module never has to import litellm to build the tuple.
_RETRYABLE_NAMES = frozenset(
    {
        "RateLimitError",
        "Timeout",
        "APITimeoutError",
        "APIConnectionError",
        "InternalServerError",
        "ServiceUnavailableError",
        "BadGatewayError",
        "TimeoutError",
        "ConnectionError",
    }
)


@dataclass(frozen=True)
class LLMConfig:
    """Which model to ask and how patiently.  ``model`` is any litellm model string."""

    model: str
    api_base: str | None = None
    api_key: str | None = None
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
        """The key to send: explicit, else a dummy for a local ``api_base``, else litellm's env."""
        if self.api_key is not None:
            return self.api_key
        return LOCAL_DUMMY_KEY if self.api_base else None


@dataclass(frozen=True)
class Completion:
    """One answer.  A cache hit carries the stored tokens/cost, ``cached=True``, ``attempts=0``."""

    text: str
    model: str
    prompt_tokens: int
    completion_tokens: int
    cost_usd: float
    latency_s: float
    cached: bool
    attempts: int
    purpose: str
    cut: str | None = None
    """``"repetition"`` when the answer ended in a repetition loop that was cut (see
    :func:`capmj.llm.stream.repetition_cut`); else None."""


@dataclass(frozen=True)
class CallRecord:
    """Accounting for one ``complete`` call, successful (``error is None``) or not; ``partial`` is
    the text a stalled or broken stream had delivered before the call failed."""

    purpose: str
    model: str
    prompt_tokens: int
    completion_tokens: int
    cost_usd: float
    latency_s: float
    cached: bool
    attempts: int
    error: str | None = None
    partial: str | None = None
    cut: str | None = None


@dataclass(frozen=True)
class Usage:
    """Totals over a client's calls.  ``cost_usd`` counts money actually spent: not cache hits."""

    calls: int
    cached_calls: int
    failed_calls: int
    prompt_tokens: int
    completion_tokens: int
    cost_usd: float
    latency_s: float


def image_part(png_bytes: bytes, *, mime: str = "image/png") -> dict[str, Any]:
    """An OpenAI-format image content part carrying ``png_bytes`` inline as a data URL."""
    if not isinstance(png_bytes, (bytes, bytearray)) or not png_bytes:
        raise ConfigError("image_part needs non-empty image bytes")
    encoded = base64.b64encode(bytes(png_bytes)).decode("ascii")
    return {"type": "image_url", "image_url": {"url": f"data:{mime};base64,{encoded}"}}


def text_part(text: str) -> dict[str, Any]:
    """An OpenAI-format text content part (to mix with :func:`image_part` in one message)."""
    return {"type": "text", "text": text}


def _import_litellm() -> ModuleType:
    os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
    import litellm

    litellm.suppress_debug_info = True  # no "Give Feedback / Get Help" banners on errors
    return litellm


MAX_RETRY_AFTER_S = 120.0
"""Longest ``Retry-After`` a provider may ask for before we give up waiting and fail the call."""

_request_gate: Any = None


def set_request_gate(gate: Any) -> None:
    """Bound the requests in flight from this process: ``gate`` is a semaphore (``acquire`` /
    ``release``), a ``multiprocessing`` one to bound them across worker processes too
    (``capmj.bench --max-llm-concurrency``), or ``None`` for no bound.  Process-wide on purpose:
    the bound is a property of the provider quota, not of one client."""
    global _request_gate
    _request_gate = gate


def request_gate() -> Any:
    """The gate :func:`set_request_gate` installed, or ``None``."""
    return _request_gate


def _retry_after(exc: BaseException) -> float | None:
    """Seconds a 429/503 answer asked us to wait (``Retry-After`` header, seconds form), if any."""
    for headers in (getattr(exc, "litellm_response_headers", None),
                    getattr(getattr(exc, "response", None), "headers", None)):
        try:
            value = headers.get("retry-after") if headers is not None else None
        except Exception:  # noqa: BLE001 - headers of unknown shape
            value = None
        if value is None:
            continue
        try:
            seconds = float(value)
        except (TypeError, ValueError):
            continue
        if math.isfinite(seconds) and seconds >= 0:
            return seconds
    return None


def _is_retryable(exc: BaseException) -> bool:
    status = getattr(exc, "status_code", None)
    if isinstance(status, int) and not isinstance(status, bool):
        if status >= 500 or status in (408, 429):
            return True
        if 400 <= status < 500:
            return False
    return any(cls.__name__ in _RETRYABLE_NAMES for cls in type(exc).__mro__)


def _int(value: object) -> int:
    return value if isinstance(value, int) and not isinstance(value, bool) and value >= 0 else 0


def _text_of(response: Any) -> str | None:
    try:
        content = response.choices[0].message.content
    except (AttributeError, IndexError, KeyError, TypeError):
        return None
    return content if isinstance(content, str) and content.strip() else None


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
        )
        with self._lock:
            self._records.append(record)

    # -- the call ---------------------------------------------------------------------------
    def complete(self, messages: Sequence[Message], *, purpose: str = "",
                 mock_response: str | None = None, temperature: float | None = None,
                 seed: int | None = None, stop: Sequence[str] = ()) -> Completion:
        """Answer ``messages`` (OpenAI chat format), from the cache when possible.

        ``temperature`` overrides ``config.temperature`` for this call; ``seed`` asks the provider
        to sample reproducibly (the OpenAI ``seed`` parameter, honoured by OpenAI, llama.cpp,
        Ollama, vLLM; not sent to providers litellm knows do not take it).  ``stop`` sequences end
        the answer (sent to the provider, and cut here too, for one that ignores them).  All three
        are part of the cache key.  ``mock_response`` (or ``config.mock_response``) makes litellm answer offline
        without any HTTP; such answers are never cached, so they cannot poison a cache used for
        real runs.  Raises :class:`LLMError` when the provider fails after all retries or answers
        no text.
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
        mock = mock_response if mock_response is not None else cfg.mock_response
        start = time.monotonic()
        key = None
        if self._cache is not None and mock is None:
            key = cache_key(model=cfg.model, api_base=cfg.api_base, messages=request,
                            temperature=temperature, max_tokens=cfg.max_tokens, seed=seed, stop=stop)
            stored = self._cache.get(key)
            if stored is not None:
                hit = Completion(
                    text=stored["text"], model=stored["model"],
                    prompt_tokens=stored["prompt_tokens"],
                    completion_tokens=stored["completion_tokens"],
                    cost_usd=float(stored["cost_usd"]), latency_s=time.monotonic() - start,
                    cached=True, attempts=0, purpose=purpose,
                )
                self._record(hit, purpose=purpose, latency=hit.latency_s, attempts=0)
                return hit
            if cfg.cache_only:
                miss = LLMError(f"cache-only: no cached completion for {purpose or 'this request'} "
                                f"(key {key[:12]}... under {cfg.cache_dir}); no live call was made. "
                                "Rerun without cache-only to ask the model.")
                self._record(None, purpose=purpose, latency=0.0, attempts=0, error=str(miss))
                raise miss
        _import_litellm()  # seconds on first use; not part of the call's latency
        start = time.monotonic()
        result, attempts, error = self._call_with_retries(request, mock, temperature, seed, stop)
        if error is not None:
            self._record(None, purpose=purpose, latency=time.monotonic() - start,
                         attempts=attempts, error=str(error), partial=error.partial)
            raise error
        completion = self._to_completion(result, start=start, attempts=attempts, purpose=purpose, stop=stop)
        if key is not None and self._cache is not None:
            self._store(key, completion)
        self._record(completion, purpose=purpose, latency=completion.latency_s, attempts=attempts)
        return completion

    def _call_with_retries(self, messages: list[dict[str, Any]], mock: str | None, temperature: float,
                           seed: int | None, stop: tuple[str, ...]) -> tuple[Any, int, LLMError | None]:
        """(response, attempts, None) on success, (None, attempts, error) on final failure; a
        failed stream's text so far is on the error (``partial``)."""
        cfg = self.config
        litellm = _import_litellm()
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
        if cfg.stream:
            kwargs.update(stream=True, stream_options={"include_usage": True})
        total = cfg.max_retries + 1
        partial: str | None = None
        for attempt in range(1, total + 1):
            gate = _request_gate
            try:
                if gate is not None:
                    gate.acquire()
                try:
                    response = litellm.completion(**kwargs)
                    if cfg.stream:
                        response = drain(response, litellm, messages)
                finally:
                    if gate is not None:
                        gate.release()
            except Exception as exc:  # every provider failure becomes LLMError below
                if isinstance(exc, StreamCut):
                    partial = exc.partial or partial
                    exc = exc.error  # noqa: PLW2901 - classify the cause, keep what arrived
                wait_s = cfg.backoff_s * 2 ** (attempt - 1)
                asked = _retry_after(exc)
                if asked is not None:
                    wait_s = max(wait_s, asked)
                if attempt < total and _is_retryable(exc) and wait_s <= MAX_RETRY_AFTER_S:
                    self._sleep(wait_s)
                    continue
                plural = "s" if attempt != 1 else ""
                got = f"; {len(partial)} characters had arrived" if partial else ""
                error = LLMError(f"{cfg.model}: {type(exc).__name__}: {_short(exc)} "
                                 f"after {attempt} attempt{plural}{got}", partial=partial)
                error.__cause__ = exc
                return None, attempt, error
            if _text_of(response) is None:
                return None, attempt, LLMError(f"{cfg.model}: response has no text content")
            return response, attempt, None
        raise AssertionError("unreachable")  # pragma: no cover

    def _to_completion(self, response: Any, *, start: float, attempts: int,
                       purpose: str, stop: tuple[str, ...] = ()) -> Completion:
        usage = getattr(response, "usage", None)
        model = getattr(response, "model", None)
        text, cut = cut_answer(_text_of(response) or "", stop)
        return Completion(
            text=text,
            cut=cut,
            model=model if isinstance(model, str) and model else self.config.model,
            prompt_tokens=_int(getattr(usage, "prompt_tokens", 0)),
            completion_tokens=_int(getattr(usage, "completion_tokens", 0)),
            cost_usd=_cost(response),
            latency_s=time.monotonic() - start,
            cached=False,
            attempts=attempts,
            purpose=purpose,
        )

    def _store(self, key: str, c: Completion) -> None:
        assert self._cache is not None
        record = {"text": c.text, "model": c.model, "prompt_tokens": c.prompt_tokens,
                  "completion_tokens": c.completion_tokens, "cost_usd": c.cost_usd,
                  "latency_s": c.latency_s, "created": time.time()}
        try:
            self._cache.put(key, record)
        except OSError as exc:  # a full disk must not throw away an answer already paid for
            _log.warning("could not write LLM cache entry: %s", exc)


@functools.lru_cache(maxsize=64)
def takes_seed(model: str, api_base: str | None = None) -> bool:
    """Whether litellm passes the OpenAI ``seed`` parameter to ``model``'s provider.

    True for ``openai/<alias>`` with an ``api_base`` (llama.cpp, vLLM, LM Studio: litellm sends
    ``seed`` in the request body as OpenAI does), ``ollama/``, ``gpt-*``; False where litellm would
    raise ``UnsupportedParamsError`` (e.g. ``anthropic/``) or does not know the model.
    """
    litellm = _import_litellm()
    try:
        name, provider, _, _ = litellm.get_llm_provider(model, api_base=api_base)
        params = litellm.get_supported_openai_params(model=name, custom_llm_provider=provider)
    except Exception:  # noqa: BLE001 - unknown model: do not send what it may reject
        return False
    return "seed" in (params or ())


def _cost(response: Any) -> float:
    """litellm's price for ``response``; 0.0 for unknown models.  Never raises."""
    try:
        litellm = _import_litellm()
        cost = float(litellm.completion_cost(completion_response=response))
    except Exception:
        return 0.0
    return cost if math.isfinite(cost) and cost >= 0 else 0.0


def _short(exc: BaseException, limit: int = 500) -> str:
    text = " ".join(str(exc).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."
