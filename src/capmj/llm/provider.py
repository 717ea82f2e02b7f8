"""What capmj needs to know about litellm and the providers behind it: the lazy import, which
failures are worth retrying and how long a provider asked us to wait, whether a model takes a
``seed``, what an answer cost, and the text of a response.

litellm is imported lazily because importing it costs seconds, and with
``LITELLM_LOCAL_MODEL_COST_MAP`` set so that the import never fetches a price list from the net.
Every function here reads a provider's answer or exception defensively: they have no common shape.
"""

from __future__ import annotations

import functools
import hashlib
import math
import os
from types import ModuleType
from typing import Any

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


def import_litellm() -> ModuleType:
    os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
    import litellm

    litellm.suppress_debug_info = True  # no "Give Feedback / Get Help" banners on errors
    return litellm


MAX_RETRY_AFTER_S = 120.0
"""Longest ``Retry-After`` a provider may ask for before we give up waiting and fail the call."""


def retry_after(exc: BaseException) -> float | None:
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


def is_retryable(exc: BaseException) -> bool:
    """Whether a failure is transient: a 5xx, 408 or 429 status, else a retryable class name."""
    status = getattr(exc, "status_code", None)
    if isinstance(status, int) and not isinstance(status, bool):
        if status >= 500 or status in (408, 429):
            return True
        if 400 <= status < 500:
            return False
    return any(cls.__name__ in _RETRYABLE_NAMES for cls in type(exc).__mro__)


def nonneg_int(value: object) -> int:
    """A token count as a provider reported it, or 0 when it is missing or not a count."""
    return value if isinstance(value, int) and not isinstance(value, bool) and value >= 0 else 0


def text_of(response: Any) -> str | None:
    """The answer's text, or None when the response has none (or only whitespace)."""
    try:
        content = response.choices[0].message.content
    except (AttributeError, IndexError, KeyError, TypeError):
        return None
    return content if isinstance(content, str) and content.strip() else None


@functools.lru_cache(maxsize=64)
def takes_seed(model: str, api_base: str | None = None) -> bool:
    """Whether litellm passes the OpenAI ``seed`` parameter to ``model``'s provider.

    True for ``openai/<alias>`` with an ``api_base`` (llama.cpp, vLLM, LM Studio: litellm sends
    ``seed`` in the request body as OpenAI does), ``ollama/``, ``gpt-*``; False where litellm would
    raise ``UnsupportedParamsError`` (e.g. ``anthropic/``) or does not know the model.
    """
    litellm = import_litellm()
    try:
        name, provider, _, _ = litellm.get_llm_provider(model, api_base=api_base)
        params = litellm.get_supported_openai_params(model=name, custom_llm_provider=provider)
    except Exception:  # noqa: BLE001 - unknown model: do not send what it may reject
        return False
    return "seed" in (params or ())


def derived_seed(key: str) -> int:
    """A request's sampling seed (the OpenAI ``seed`` parameter) derived from ``key`` alone, so the
    same request gets the same seed in any process (and the LLM cache key holds).  31 bits: valid
    for llama.cpp (uint32, where -1 means random) and OpenAI alike."""
    return int.from_bytes(hashlib.sha256(key.encode()).digest()[:4], "big") & 0x7FFF_FFFF


def cost(response: Any) -> float:
    """litellm's price for ``response``; 0.0 for unknown models.  Never raises."""
    try:
        litellm = import_litellm()
        cost = float(litellm.completion_cost(completion_response=response))
    except Exception:
        return 0.0
    return cost if math.isfinite(cost) and cost >= 0 else 0.0


def short(exc: BaseException, limit: int = 500) -> str:
    """An exception's message on one line, at most ``limit`` characters (for an LLMError)."""
    text = " ".join(str(exc).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."
