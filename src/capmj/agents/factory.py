"""Build an agent from its name and options: ``make_agent("oracle")``, ``make_agent("llm", model=...)``.

Agents are resolved lazily by import path, so asking for the oracle never imports the LLM stack
(litellm takes seconds to import) and an agent whose module is not written or installed yet gives a
:class:`ConfigError` naming the valid agents instead of an ``ImportError`` deep in a worker.

Options whose value is ``None`` are dropped before the agent is built, so a command line can pass
every LLM flag it has (``model=None, reporter=None, ...``) and each agent only sees the options the
user actually set.  An agent that does not accept an option the user set is a ``ConfigError``.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import inspect
from typing import Any

from capmj.errors import ConfigError

AGENTS: dict[str, str] = {
    "oracle": "capmj.agents.oracle:OracleAgent",
    "reference": "capmj.agents.reference:ReferenceAgent",
    "llm": "capmj.agents.llm_agent.agent:LLMAgent.from_options",
}
"""Agent name -> ``module:attribute`` of its class or of a factory taking keyword options
(``attribute`` may be dotted: the LLM agent's flat options go through ``LLMAgent.from_options``,
which builds its typed configuration and rejects unknown names itself)."""


def _load(name: str) -> Any:
    if name not in AGENTS:
        raise ConfigError(f"unknown agent {name!r}; valid agents: {', '.join(AGENTS)}")
    module, _, attr = AGENTS[name].partition(":")
    try:
        mod = importlib.import_module(module)
    except ModuleNotFoundError as exc:
        if exc.name and (exc.name == module or module.startswith(exc.name + ".")):
            avail = [n for n in AGENTS if n == "oracle" or _importable(AGENTS[n])]
            raise ConfigError(f"agent {name!r} is not available in this installation ({module} is missing); "
                              f"available agents: {', '.join(avail)}") from None
        raise ConfigError(f"agent {name!r} could not be imported: {type(exc).__name__}: {exc}") from exc
    except ImportError as exc:
        raise ConfigError(f"agent {name!r} could not be imported: {type(exc).__name__}: {exc}") from exc
    try:
        return functools.reduce(getattr, attr.split("."), mod)
    except AttributeError:
        raise ConfigError(f"agent {name!r} is not available: {module} has no {attr!r}; "
                          f"valid agents: {', '.join(AGENTS)}") from None


def _importable(path: str) -> bool:
    module = path.partition(":")[0]
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def make_agent(name: str, **options: Any) -> Any:
    """An agent instance.  ``None``-valued options are ignored; unknown ones raise ``ConfigError``."""
    factory = _load(name)
    opts = {k: v for k, v in options.items() if v is not None}
    if opts:
        try:
            params = inspect.signature(factory).parameters
        except (TypeError, ValueError):  # builtins / C types: let the call decide
            params = None
        if params is not None and not any(p.kind is p.VAR_KEYWORD for p in params.values()):
            bad = sorted(set(opts) - set(params))
            if bad:
                accepted = [p for p in params if p != "self"]
                raise ConfigError(f"agent {name!r} does not take option(s) {', '.join(bad)}; "
                                  f"it accepts: {', '.join(accepted) or 'no options'}")
    try:
        return factory(**opts)
    except ConfigError:
        raise
    except TypeError as exc:
        raise ConfigError(f"agent {name!r} rejected its options {sorted(opts)}: {exc}") from exc


def agent_setting(agent: Any, name: str, default: Any = None) -> Any:
    """One setting of a built agent, for records that describe any agent (the run manifest, the
    price check): from its options record when it has one (the LLM agent's ``options``), else
    from the attribute of that name (the reference agent's ``perception``, ``budget``)."""
    options = getattr(agent, "options", None)
    if options is not None and hasattr(options, name):
        return getattr(options, name)
    return getattr(agent, name, default)


def has_setting(agent: Any, name: str) -> bool:
    """Whether :func:`agent_setting` finds ``name`` on ``agent``."""
    return hasattr(getattr(agent, "options", None), name) or hasattr(agent, name)


__all__ = ["AGENTS", "agent_setting", "has_setting", "make_agent"]
