"""One attempt of the LLM agent's closed loop, as recorded in ``llm.attempts`` of an episode.

The LLM agent (:mod:`capmj.agents.llm_agent.agent`) builds one :class:`AttemptRecord` per attempt; the
readers of ``episodes.jsonl`` (failure attribution, loop statistics, export, replay-check) read its
attributes.  The meaning of every field is written once, in :data:`ATTEMPT_FIELDS`, which the docs
and a test check against the dataclass.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from capmj.records.codec import from_plain, to_plain

__all__ = ["ATTEMPT_FIELDS", "CALL_FORMS", "LOOP_RULES", "ApiError", "AttemptRecord", "ToolCallRecord"]

LOOP_RULES: dict[str, str] = {
    "achieved": "the reporter said achieved: stop",
    "finished": "no reporter and the plan finished: stop",
    "not_achieved": "the reporter said not achieved: reset the scene and re-plan",
    "unknown_replan": "unknown verdict, --on-unknown replan: reset and re-plan",
    "unknown_stop": "unknown verdict, --on-unknown stop: stop",
    "error": "the plan raised (judged not achieved, or not judged): reset and re-plan with the error",
    "not_run": "the plan was identical to an earlier one and not run: re-plan",
    "achieved_after_error": "careful: the plan raised after acting, the reporter judged the reached state "
                            "achieved: stop there (error recorded, state kept)",
    "partial_replan": "careful: not achieved, the reporter named some (not all) movable objects wrong: "
                      "re-plan from the current state, no reset",
    "low_confidence_stop": "careful: the verdict is low-confidence (capmj.agents.report.confidence): stop, keep the state",
    "llm_error": "the LLM provider failed: stop",
    "llm_budget": "the episode's LLM budget is used up: stop",
    "finish": "multi-turn: the model answered FINISH: stop (the scene as it is)",
    "next_turn": "multi-turn: no FINISH: the model gets the turn's feedback and answers again, no reset",
    "max_turns": "multi-turn: the last turn (--max-turns) ended without FINISH: stop",
    "answered": "--policy tools: the model answered without a tool call: stop (the scene as it is)",
}
"""What the loop decided after an attempt (``rule`` of an attempt record), by
:func:`capmj.agents.llm_agent.loop_policy.decide`.  The loop also stops when the attempts are used up
(``LLMNotes.stopped``), whatever the rule."""

ATTEMPT_FIELDS: dict[str, str] = {
    "attempt": "1, 2, ...",
    "reset": "the scene was reset to the initial state before this attempt",
    "temperatures": "sampling temperature of each planner request of this attempt, in order",
    "seeds": "sampling seed sent with each planner request (None: none sent; attempt 1 sends none)",
    "code": "the plan as it ran (after import clean-up and parse_function), None without code; "
            "for a plan not run, the answer's code",
    "code_differs": "the plan differs from every earlier attempt's plan (None for attempt 1)",
    "identical_to": "the earliest earlier attempt with the same plan, else None",
    "extra_requests": "planner requests made because an answer repeated an earlier attempt's plan",
    "not_run": "why the plan was not run ('identical to attempt 1 after 3 retries; not re-run'), else None; "
               "the scene then ends where that attempt's plan ended",
    "error": "the plan's error ('PlanError: line 3: ...'), None when it finished",
    "error_kind": "'plan' or 'llm' (only when error is set)",
    "error_line": "line of the plan the error points at, else None",
    "error_type": "the class of what failed (capmj.errors.error_facts: 'SandboxViolation', 'MotionFailed', "
                  "'IndexError', ...; only when error is set)",
    "error_status": "the failed primitive's status for a MotionFailed ('unreachable', 'no_path', 'no_grip', 'wrong_object')",
    "failed_program": "which program failed: 'planner' or the helper LMP's name (only when error is set)",
    "api_error": "the error the plan's last API call raised, when the attempt's error is that one ({fn, error})",
    "verdict": "the reporter's verdict: True, False, or None (unknown, no reporter, or the plan failed)",
    "verdict_source": "'code', 'repair', 'direct' or 'unknown'; None when no reporter ran",
    "reason": "the reporter's one-line reason",
    "wrong": "objects whose state the reporter says is wrong",
    "reporter_errors": "problems met on the way to the verdict ('code: ...', 'repair: ...')",
    "reporter_error": "why the reporter reached no verdict (only when it says so)",
    "predicate": "the task's success predicate on the state the reporter judged (None if it failed)",
    "predicate_progress": "the predicate's progress in [0, 1] on that state",
    "on_unknown": "the policy applied to an unknown verdict ('replan'/'stop'), else None",
    "confidence": "the verdict's confidence, 'high' or 'low' (capmj.agents.report.confidence.assess); None without a reporter",
    "low_confidence": "why it is low (a key of capmj.agents.report.confidence.LOW_CONFIDENCE), else None",
    "rule": "which loop rule fired after this attempt (a key of LOOP_RULES)",
    "report": "what the next attempt is told (verdict/error and object positions)",
    "primitives": "pick-and-place calls", "api_calls": "planner API calls",
    "llm_calls": "LLM calls", "prompt_tokens": "prompt tokens", "completion_tokens": "completion tokens",
    "said": "messages of the plan's say()",
    "finish": "multi-turn only: the answer said FINISH (its code, if any, ran first); absent in single-turn records",
    "feedback": "multi-turn only: the feedback message's text sent after this turn (None after the last; "
                "a turn's report stays empty)",
    "images": "multi-turn only: camera images sent with that feedback (0 with --feedback text)",
    "described": "multi-turn --feedback describe only: the describing model's account of what changed",
    "tool_calls": "--policy tools only: the turn's function calls in order, each with its arguments, its form "
                  "(CALL_FORMS), its JSON result or its error; absent in code-policy records",
}
"""The keys of every attempt record in ``llm.attempts`` and their meaning."""


@dataclass(frozen=True)
class ApiError:
    """The exception an API function raised in the plan's last call (``fn`` is its name)."""

    fn: str | None
    error: str

    def to_dict(self) -> dict[str, Any]:
        return to_plain(self)

    @classmethod
    def from_dict(cls, data: Any, *, strict: bool = True) -> "ApiError":
        return from_plain(cls, data, strict=strict)


CALL_FORMS: dict[str, str] = {
    "tool_calls": "the answer's tool_calls, as the OpenAI API defines them",
    "content_json": "a JSON object {\"name\", \"arguments\"} written in the answer's text instead (small models do)",
}
"""How a model wrote a function call (``form`` of a :class:`ToolCallRecord`)."""


@dataclass(frozen=True)
class ToolCallRecord:
    """One function call of a ``--policy tools`` turn: ``arguments`` as the model wrote them (JSON
    text), ``form`` a key of :data:`CALL_FORMS`, and what went back to the model: ``result`` (the
    value as JSON) or ``error``."""

    id: str
    name: str
    arguments: str
    form: str
    result: str | None = None
    error: str | None = None

    OMIT_IF_NONE: ClassVar[frozenset[str]] = frozenset({"result", "error"})

    def to_dict(self) -> dict[str, Any]:
        return to_plain(self)

    @classmethod
    def from_dict(cls, data: Any, *, strict: bool = True) -> "ToolCallRecord":
        return from_plain(cls, data, strict=strict)


@dataclass(frozen=True)
class AttemptRecord:
    """What one attempt did and how it ended (fields: :data:`ATTEMPT_FIELDS`)."""

    attempt: int
    reset: bool = False
    temperatures: tuple[float, ...] = ()
    seeds: tuple[int | None, ...] = ()
    code: str | None = None
    code_differs: bool | None = None
    identical_to: int | None = None
    extra_requests: int = 0
    not_run: str | None = None
    error: str | None = None
    error_kind: str | None = None
    error_line: int | None = None
    error_type: str | None = None
    error_status: str | None = None
    failed_program: str | None = None
    api_error: ApiError | None = None
    verdict: bool | None = None
    verdict_source: str | None = None
    reason: str = ""
    wrong: tuple[str, ...] = ()
    reporter_errors: tuple[str, ...] = ()
    reporter_error: str | None = None
    predicate: bool | None = None
    predicate_progress: float | None = None
    on_unknown: str | None = None
    confidence: str | None = None
    low_confidence: str | None = None
    rule: str | None = None
    report: str = ""
    primitives: int = 0
    api_calls: int = 0
    llm_calls: int = 0
    prompt_tokens: int = 0
    completion_tokens: int = 0
    said: tuple[str, ...] = ()
    finish: bool | None = None
    feedback: str | None = None
    images: int | None = None
    described: str | None = None
    tool_calls: tuple[ToolCallRecord, ...] | None = None

    OMIT_IF_NONE: ClassVar[frozenset[str]] = frozenset({"error_kind", "error_type", "error_status",
                                                         "failed_program", "api_error", "reporter_error",
                                                         "finish", "feedback", "images", "described", "tool_calls"})
    """Keys present only with an error (or, ``reporter_error``, a reporter's own error), as written
    before records were typed; and the turn keys of a multi-turn episode (issue #47), absent from
    single-turn records, so those are written and read exactly as before."""
    DEFAULT_IF_MISSING: ClassVar[frozenset[str]] = frozenset({"confidence", "low_confidence", "rule"})
    """Keys added after ``capmj.episode/2`` was first written (issue #26's loop policies): a line
    without them reads as their defaults."""

    def to_dict(self) -> dict[str, Any]:
        return to_plain(self)

    @classmethod
    def from_dict(cls, data: Any, *, strict: bool = True) -> "AttemptRecord":
        return from_plain(cls, data, strict=strict)
