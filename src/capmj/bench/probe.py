"""One request before a grid starts: is the model's server there, and does it take the key?

Without it, a wrong port, a refused key or an unknown model becomes a column of failed episodes,
each after the client's retries.  :func:`probe_agents` asks once per (model, server) of the grid's
LLM agents and raises :class:`~capmj.errors.ModelUnreachable` (a ``ConfigError``: one line, exit
2) when the answer says the run cannot work:

* a self-hosted server (``--api-base``): ``GET <api-base>/models``, the OpenAI-compatible listing
  that llama.cpp, vLLM, Ollama's ``/v1`` and LM Studio serve.  No connection, a timeout, or HTTP
  401/403 fail; any other answer (a server without the route answers 404) passes, since only the
  server's presence and the key are in question.  It costs no completion and no scripted answer.
* a cloud provider (no ``--api-base``): one chat completion of at most a few tokens, not cached;
  any provider error (no key, a refused key, an unknown model) fails.

Not probed: runs answered from the cache alone (``--cache-only``), mocked answers, agents without
an LLM.  ``--no-probe`` skips it.
"""

from __future__ import annotations

import urllib.error
import urllib.request
from dataclasses import replace
from typing import Any, Iterable

from capmj.errors import LLMError, ModelUnreachable

PROBE_TIMEOUT_S = 15.0
"""Seconds the listing request may take (a server that does not answer it in this time will not
answer the planner either)."""
PROBE_MESSAGE = "Reply with the single word OK."


def probe_agents(agents: Iterable[Any]) -> None:
    """Probe each distinct (model, server) of ``agents`` once (see the module docstring)."""
    seen: set[tuple[str, str | None]] = set()
    for agent in agents:
        cfg = getattr(agent, "config", None)
        if cfg is None or not hasattr(cfg, "model") or cfg.cache_only or cfg.mock_response is not None:
            continue
        key = (cfg.model, cfg.api_base)
        if key in seen:
            continue
        seen.add(key)
        if cfg.api_base:
            probe_server(cfg.model, cfg.api_base, cfg.resolved_api_key)
        else:
            probe_completion(cfg)


def probe_server(model: str, api_base: str, api_key: str | None) -> None:
    """``GET <api_base>/models``; :class:`ModelUnreachable` when nothing answers or the key is refused."""
    url = api_base.rstrip("/") + "/models"
    request = urllib.request.Request(url, headers={"Authorization": f"Bearer {api_key}"} if api_key else {})
    hint = "check --api-base and that the server is running, or add --no-probe to start anyway"
    try:
        with urllib.request.urlopen(request, timeout=PROBE_TIMEOUT_S) as response:  # noqa: S310 - the user's server
            response.read(1 << 16)
    except urllib.error.HTTPError as exc:
        if exc.code in (401, 403):
            raise ModelUnreachable(f"model {model} at {api_base}: the server refused the key (HTTP {exc.code} on "
                                   f"{url}); check --api-key or the provider's key variable") from None
        return  # the server is there; a missing listing route says nothing about the model
    except (urllib.error.URLError, OSError, ValueError) as exc:
        reason = getattr(exc, "reason", exc)
        raise ModelUnreachable(f"model {model} at {api_base}: the server did not answer ({reason}); {hint}") from None


def probe_completion(cfg: Any) -> None:
    """One tiny, uncached completion through the LLM client; :class:`ModelUnreachable` on any provider error."""
    from capmj.llm.client import LLMClient

    quick = replace(cfg, cache_dir=None, max_tokens=8, max_retries=min(cfg.max_retries, 1))
    try:
        LLMClient(quick).complete([{"role": "user", "content": PROBE_MESSAGE}], purpose="probe")
    except LLMError as exc:
        raise ModelUnreachable(f"model {cfg.model}: a probe request failed ({exc}); check the model name and the "
                               "provider's key, or add --no-probe to start anyway") from None


__all__ = ["PROBE_MESSAGE", "PROBE_TIMEOUT_S", "probe_agents", "probe_completion", "probe_server"]
