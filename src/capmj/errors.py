"""The capmj exception hierarchy.

Every error capmj raises on purpose derives from :class:`CapmjError`, so a benchmark runner can
record "ErrorClass: message" for one episode and go on with the next without catching unrelated
bugs by accident.
"""

from __future__ import annotations


class CapmjError(Exception):
    """Base of every deliberate capmj error."""


class ConfigError(CapmjError, ValueError):
    """Bad user input: unknown name, malformed range, unwritable folder.  Names the valid choices."""


class RecordError(CapmjError, ValueError):
    """A stored record (a line of ``episodes.jsonl``, an attempt) does not match its schema: an
    unknown or missing key, or a value of the wrong type.  Names the record type and the key."""


class SimError(CapmjError):
    """The MuJoCo world could not be built, rendered or stepped."""


class RenderBackendError(SimError):
    """No headless OpenGL backend (EGL or OSMesa) could be initialised."""


class TaskError(CapmjError):
    """A task is malformed: bad scene, impossible goal, failing generator."""


class PluginError(TaskError):
    """A task plugin failed to load or clashes with another one; names the distribution."""


class AgentError(CapmjError):
    """An agent could not act (e.g. the oracle found no valid target)."""


class PlanError(AgentError):
    """LLM-written code was rejected by the sandbox or raised while running.

    ``line`` is the 1-based line of the offending statement in the submitted code when known.
    """

    def __init__(self, message: str, *, line: int | None = None, code: str | None = None) -> None:
        super().__init__(message if line is None else f"line {line}: {message}")
        self.line = line
        self.code = code


class BudgetExceeded(PlanError):
    """LLM code used more wall time, API calls or simulation steps than its budget."""


class LLMError(AgentError):
    """The LLM provider failed (timeout, HTTP error, malformed answer) after all retries."""
