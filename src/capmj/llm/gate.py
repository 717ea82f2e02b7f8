"""The process-wide bound on LLM requests in flight.

Process-wide on purpose: the bound is a property of the provider quota, not of one client, so
every :class:`~capmj.llm.client.LLMClient` of a worker process passes through the one gate.
"""

from __future__ import annotations

from typing import Any

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
