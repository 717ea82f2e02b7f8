"""API keys: taken out of the environment once, handed to the LLM client explicitly.

Processes that run LLM-written code (plans, helper LMPs, reporters' checking code) must not hold
keys where that code could read them, and the environment is the first place any escape looks
(``os.environ``, ``/proc/self/environ``, a child process's environment).  So a command that runs
such code calls :func:`take_secrets` when it starts: every secret-looking variable
(:func:`is_secret_name`, the one rule) leaves ``os.environ`` and is kept in this module, and the
worker processes it spawns inherit an environment without them.  The LLM client still gets its
key: :func:`api_key_for` finds the variable the model's provider reads (litellm's own list,
consulted lazily) among the taken secrets (or, in a process that took none, in the environment),
:class:`~capmj.llm.config.LLMConfig.resolved_api_key` asks it, and the client passes the result
to litellm as ``api_key``.  A worker process gets the key inside its agent's configuration (the
bench's ``AgentSpec``), never through its environment.

What this does not do: providers that need several secret variables at once (AWS Bedrock's
``AWS_ACCESS_KEY_ID`` and ``AWS_SECRET_ACCESS_KEY``, Vertex AI's credentials file) get the first
as ``api_key`` only; give such a provider a proxy with one key (``--api-base``).
"""

from __future__ import annotations

import functools
import os
import re
from collections.abc import Mapping, MutableMapping

__all__ = ["SECRET_NAME", "api_key_for", "is_secret_name", "secret_free", "take_secrets", "taken_secrets"]

SECRET_NAME = re.compile(r"SECRET|PASSWORD|PASSWD|CREDENTIAL|(?:^|_)(?:KEY|APIKEY|TOKEN|AUTH|COOKIE)(?:_|$)")
"""The rule: a variable is a secret when its upper-cased name contains ``SECRET``, ``PASSWORD``,
``PASSWD`` or ``CREDENTIAL``, or has ``KEY``, ``APIKEY``, ``TOKEN``, ``AUTH`` or ``COOKIE`` as one
of its ``_``-separated words: ``OPENAI_API_KEY``, ``ANTHROPIC_AUTH_TOKEN``, ``HF_TOKEN``,
``AWS_ACCESS_KEY_ID``, ``AWS_SECRET_ACCESS_KEY``, ``GOOGLE_APPLICATION_CREDENTIALS``,
``SSH_AUTH_SOCK``, ``PGPASSWORD``; not ``TOKENIZERS_PARALLELISM`` or ``KEYBOARD``."""

_taken: dict[str, str] = {}
"""The secrets :func:`take_secrets` removed from this process's environment."""


def is_secret_name(name: str) -> bool:
    """Whether an environment variable of this name holds a secret (:data:`SECRET_NAME`)."""
    return SECRET_NAME.search(name.upper()) is not None


def secret_free(environ: Mapping[str, str]) -> dict[str, str]:
    """A copy of ``environ`` without its secrets (the ``env`` of a process that runs LLM code)."""
    return {k: v for k, v in environ.items() if not is_secret_name(k)}


def take_secrets(environ: MutableMapping[str, str] | None = None) -> dict[str, str]:
    """Remove every secret from ``environ`` (default: ``os.environ``) and keep it here for
    :func:`api_key_for`; returns every secret taken so far.  Idempotent: call it when a command
    that runs LLM-written code starts, before it starts any worker."""
    env = os.environ if environ is None else environ
    for name in [k for k in env if is_secret_name(k)]:
        _taken[name] = env.pop(name)
    return dict(_taken)


def taken_secrets() -> dict[str, str]:
    """The secrets taken from this process's environment so far (a copy)."""
    return dict(_taken)


@functools.lru_cache(maxsize=32)
def provider_key_names(model: str, api_base: str | None = None) -> tuple[str, ...]:
    """The environment variables litellm reads ``model``'s key from, in its order of preference
    (``OPENAI_API_KEY`` for ``gpt-4o-mini``, ``GEMINI_API_KEY`` and ``GOOGLE_API_KEY`` for
    ``gemini/...``), then ``<PROVIDER>_API_KEY``; only names that are secrets by the rule.
    Imports litellm (seconds, once): call it when a key is needed, never at import.  Cached per
    process (litellm is asked with the environment's secrets set aside, once)."""
    from capmj.llm.provider import import_litellm

    litellm = import_litellm()
    names: list[str] = []
    saved = {k: os.environ.pop(k) for k in [k for k in os.environ if is_secret_name(k)]}
    try:  # litellm lists only the variables it finds missing: ask it with none present
        names.extend(litellm.validate_environment(model=model, api_base=api_base).get("missing_keys") or [])
        provider = litellm.get_llm_provider(model, api_base=api_base)[1]
    except Exception:  # noqa: BLE001 - litellm raises for a model it does not know
        provider = model.split("/", 1)[0] if "/" in model else None
    finally:
        os.environ.update(saved)
    if provider:
        names.append(f"{str(provider).upper()}_API_KEY")
    return tuple(dict.fromkeys(n for n in names if is_secret_name(n)))


def api_key_for(model: str, api_base: str | None = None) -> str | None:
    """The key ``model``'s provider needs, from the secrets taken from this process's environment
    (or still in it, where none were taken); None when none of its variables is set."""
    pool = {**{k: v for k, v in os.environ.items() if is_secret_name(k)}, **_taken}
    if not pool:
        return None
    for name in provider_key_names(model, api_base):
        if pool.get(name):
            return pool[name]
    return None
