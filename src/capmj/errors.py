"""The capmj exception hierarchy.

Every error capmj raises on purpose derives from :class:`CapmjError`, so a benchmark runner can
record "ErrorClass: message" for one episode and go on with the next without catching unrelated
bugs by accident.

A kind of failure is a class, not a message prefix: an episode records the class of what went
wrong (:func:`error_facts`: ``error_type`` and, for a motion, its ``status``), and failure
attribution (:mod:`capmj.bench.failures`) switches on that class.  Classes that were introduced
after their failures were already raised under a more general class keep that class's name in
their text (``shown_as``; see :func:`describe`): the text is what the LLM is shown on a re-plan,
what cached completions were asked with and what published records hold, so a new class must not
change a single character of it.  An error once raised as a PlanError with its kind written at the
start of its message shows both names (``shown_as = "PlanError: ValueError"``): the kind is its
class now, and its text reads as it always did.
"""

from __future__ import annotations

import builtins
from typing import ClassVar


class CapmjError(Exception):
    """Base of every deliberate capmj error."""

    shown_as: ClassVar[str | None] = None
    """The class name (or names, ``"PlanError: ValueError"``) this error's text shows (None: its own name)."""

    def __repr__(self) -> str:
        return f"{error_name(self)}({', '.join(map(repr, self.args))})"


class ConfigError(CapmjError, ValueError):
    """Bad user input: unknown name, malformed range, unwritable folder.  Names the valid choices."""


class ModelUnreachable(ConfigError):
    """The model a run names cannot be asked: its server did not answer the start-up probe, refused
    the key, or the provider refused the request (``capmj.bench.probe``).  The run does not start."""


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


class ConfinementError(PluginError):
    """LLM-written task code cannot run confined or broke its confinement: no jail on this machine,
    refused by the static check or the runtime guard, a malformed message from the jail, or a
    package changed since it was accepted.  Such code never runs outside the jail."""


class UnverifiedPackage(ConfinementError):
    """A generated package is not the package that was accepted (a file added or changed, a module
    failing the static check, an unreadable or older manifest); ``problems`` says each way."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("; ".join(problems[:5]))
        self.problems = problems


class GuardRefused(ConfinementError):
    """The runtime guard in the jail refused an event of generated code (``event``, ``detail``)."""

    def __init__(self, event: str, detail: str) -> None:
        super().__init__(f"refused by the runtime guard: {detail}")
        self.event, self.detail = event, detail


class ConfinedTaskError(TaskError):
    """LLM-written task code failed inside its jail: it raised (``remote_type`` names the class it
    raised), or a limit of the jail ended it (CPU, memory, wall time)."""

    def __init__(self, message: str, remote_type: str | None = None) -> None:
        super().__init__(message)
        self.remote_type = remote_type


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


class NoCodeError(PlanError):
    """An LLM answer held no code to run (prose only, or an empty code block)."""

    shown_as = "PlanError"


class PlanSyntaxError(PlanError):
    """LLM-written code does not parse (or compile)."""

    shown_as = "PlanError"


class SandboxViolation(PlanError):
    """LLM-written code uses what the sandbox does not allow (imports, private attributes, ...)."""

    shown_as = "PlanError"


class CheckArgumentError(PlanError):
    """A relation check or selector of the ``relations`` reporter was given what it cannot read: no
    object or place of the scene, a size, area or side it does not know.  The message names the
    valid choices, which the repair request quotes.  Not a ``ValueError``: a check's ``except
    ValueError`` does not catch it (it never did)."""

    shown_as = "PlanError: ValueError"


class UnknownCheckError(PlanError):
    """A ``relations`` answer calls a name its prompt does not define; the message names the checks
    and selectors there are.  Not a ``NameError`` (it never was)."""

    shown_as = "PlanError: NameError"


class FunctionNotWritten(PlanError):
    """LLM code calls a function that ``parse_function`` could not supply: the answer defined other
    names, or the synthesis depth was reached.  Not a ``NameError`` (it never was)."""

    shown_as = "PlanError: NameError"


class ReturnNotSet(PlanError):
    """A helper LMP's code finished without setting its return variable.  Not a ``NameError``."""

    shown_as = "PlanError: NameError"


class BudgetExceeded(PlanError):
    """LLM code used more wall time, API calls or simulation steps than its budget."""


class LLMBudgetExceeded(BudgetExceeded):
    """The episode's LLM calls used more tokens or money than ``episode_max_*`` allows."""


class HelperCallsExceeded(LLMBudgetExceeded):
    """The episode's code called helper LMPs (``parse_obj_name``, ``parse_position``,
    ``parse_question``, ``parse_function``, a plan's ``parse_completion``) more often than
    ``episode_max_helper_calls`` allows; refused before the LLM is asked."""


class TextBudgetExceeded(BudgetExceeded):
    """Text made from a plan value (``say``, ``print``, ``str``/``repr``, f-strings, ``format``,
    ``%``, a helper's return value) would pass its character cap; refused before it is made."""


class MotionFailed(AgentError, RuntimeError):
    """A pick-and-place the plan asked for did not happen: ``status`` is the primitive's
    (``unreachable``, ``no_grip``; ``wrong_object`` when it picked another object than asked).
    A ``RuntimeError`` too, as plan code written against the original API catches it."""

    shown_as: ClassVar[str | None] = "RuntimeError"

    def __init__(self, message: str, *, status: str) -> None:
        super().__init__(message)
        self.status = status


class PerceptionFailed(MotionFailed):
    """A pick-and-place missed because perception put the object elsewhere than it is (the
    perceived pick point lies off the object the plan named, or at an object that is not there;
    ``--perception rgbd``).  The robot sees only the miss, so the text is the motion failure's; the
    class, recorded as ``error_type``, tells failure attribution that perception caused it."""


class MotionPlanningError(MotionFailed):
    """No collision-free path for a move: every straight way would make an arm link, the suction
    cup or the carried object touch what it is not meant to, and the planner found no way around
    (or the target itself is inside something).  Raised before the arm moves; ``status`` is
    ``no_path``.  Failure attribution labels it ``motion``."""

    shown_as: ClassVar[str | None] = None


class UnreachablePose(MotionFailed):
    """A low-level move (``--api low``) the robot cannot make: no IK solution on its path (out of
    reach, beyond a joint limit) or a target below the table top.  Refused before the arm moves;
    ``status`` is ``unreachable`` or ``below_table``."""

    shown_as = None


class CollisionDetected(MotionFailed):
    """A low-level move (``--api low``) touched what it was not meant to: an arm link, the tool or
    the carried object met the table or an object on the way.  The arm stops there; ``status`` is
    ``collision``."""

    shown_as = None


class UnknownObjectError(AgentError, ValueError):
    """Plan code named an object (or obj_id) the scene does not have.  A ``ValueError`` too, as it
    always was.  ``name`` is the name (or id) as the code wrote it, when known."""

    shown_as = "ValueError"

    def __init__(self, message: str, *, name: object = None) -> None:
        super().__init__(message)
        self.name = name


class PortingDifference(AgentError, ValueError):
    """Plan code used the API as CapRavens' did where capmj deliberately differs (bowls are fixed,
    ...).  The message names the difference; the porting table of ``docs/llm.md`` lists each one,
    and ``benchmarks/capravens_examples.py`` counts an example failing with it as needing a
    documented mapping.  Shown as ``ValueError``, the class these errors were raised under before."""

    shown_as = "ValueError"


class LLMError(AgentError):
    """The LLM provider failed (timeout, HTTP error, malformed answer) after all retries.

    ``partial`` is the text a streamed answer had delivered before it stalled or broke (else None).
    """

    def __init__(self, message: str, *, partial: str | None = None) -> None:
        super().__init__(message)
        self.partial = partial


class ToolCallingUnsupported(ConfigError):
    """``--policy tools`` with a model that has no tool calling (its provider's model list says
    so); raised when the agent is built, before any episode, naming the model."""


class ToolsRejected(LLMError):
    """The server answered a request that offered ``tools`` with a refusal of them (its model or
    its configuration has no tool calling); names the model.  Ends the episode as a provider failure."""


class InfrastructureError(CapmjError):
    """The episode could not be run or judged through no fault of the agent (recorded by name;
    the benchmark attributes these to ``infrastructure``)."""


class WorkerCrash(InfrastructureError):
    """The worker process died running the episode, twice (the second time running it alone)."""


class WorkerError(InfrastructureError):
    """The worker's result could not be returned (e.g. it failed to unpickle)."""


class EvaluationFailed(InfrastructureError):
    """The task's evaluation raised on the final state."""


def error_name(exc: BaseException) -> str:
    """The class name an error's text shows (``shown_as``, else its class's name)."""
    return getattr(type(exc), "shown_as", None) or type(exc).__name__


def describe(exc: BaseException) -> str:
    """``"ErrorClass: message"``, the one form in which errors are recorded and shown to the LLM."""
    return f"{error_name(exc)}: {exc}"


def inner_text(exc: BaseException) -> str:
    """:func:`describe` without a leading ``"PlanError: "``: the text a plan error is quoted with
    inside another error's message (``"NameError: ..."`` for a class shown as ``PlanError: NameError``,
    the bare message for one shown as ``PlanError``)."""
    text = describe(exc)
    return text[len("PlanError: "):] if text.startswith("PlanError: ") else str(exc)


def error_facts(exc: BaseException) -> tuple[str, str | None]:
    """``(error_type, status)`` of an error: the class name of what really happened, and its
    ``status`` when it has one (:class:`MotionFailed`).

    The sandbox re-raises what plan code or an API function raised as a located PlanError *from*
    it, so below a PlanError the ``__cause__`` chain is followed to its end.  Other errors are
    taken as they are (an LLMError's cause is the provider library's own exception).
    """
    root, seen = exc, {id(exc)}
    while isinstance(root, PlanError) and root.__cause__ is not None and id(root.__cause__) not in seen:
        root = root.__cause__
        seen.add(id(root))
    status = getattr(root, "status", None)
    return type(root).__name__, status if isinstance(status, str) else None


def error_class(name: str | None) -> type[BaseException] | None:
    """The class a recorded ``error_type`` names: a class of this module or a built-in exception;
    None for any other (a third-party error, or no error)."""
    if not name:
        return None
    cls = globals().get(name) or getattr(builtins, name, None)
    return cls if isinstance(cls, type) and issubclass(cls, BaseException) else None
