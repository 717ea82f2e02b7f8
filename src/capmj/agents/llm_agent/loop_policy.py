"""What the closed loop does after an attempt: the ``thesis`` and the ``careful`` policy.

``thesis`` (the default, the loop as the thesis describes it): a True verdict stops; a False
verdict, an error or a plan not run resets the scene to its initial state and re-plans; an unknown
verdict follows ``--on-unknown``.  A plan that raised is not judged.

``careful`` (issue #26) changes three things:

a. **judge before resetting.** A plan that raised *after acting* is judged on the state it
   reached.  Achieved: the episode stops there (``achieved_after_error``; the error stays in the
   attempt record, the state is kept).
b. **re-plan from here.** A high-confidence "not achieved" naming some, not all, of the movable
   objects re-plans from the current state without a reset (``partial_replan``), told which
   objects are wrong, so the objects the plan placed right stay where they are.
c. **stop on low confidence.** A verdict :func:`capmj.agents.report.confidence.assess` finds
   low-confidence (unknown, "not achieved" naming no real movable object, self-contradicting)
   keeps the state instead of re-planning from scratch (``low_confidence_stop``): such a verdict
   is no evidence that the state is wrong.  After a plan that raised, a low-confidence verdict
   does not stop: the error is evidence, so the thesis rule (``error``: reset and re-plan)
   applies -- and the next plan is not told that verdict (:attr:`Decision.shows_report`), so it is
   asked exactly what the loop without a reporter asks.

The failure of the thesis loop that each rule answers: ``docs/llm.md``, "Loop policies".

Without a reporter both policies are the same.  Their names: :data:`capmj.agents.choices.LOOP_POLICIES`.  The rules are named in
:data:`capmj.records.LOOP_RULES`; :func:`decide` is the one place that chooses among them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from capmj.agents.choices import LOOP_POLICIES
from capmj.agents.report.confidence import Assessment
from capmj.errors import ConfigError
from capmj.records import LOOP_RULES

__all__ = ["Decision", "Outcome", "check_policy", "decide", "judges_errors", "wrong_share"]



@dataclass(frozen=True)
class Outcome:
    """What the loop knows when one attempt ends."""

    not_run: bool = False
    """The plan was identical to an earlier one and not run."""
    error: bool = False
    """The plan (or a helper LMP) raised; LLM provider failures and budgets are decided elsewhere."""
    verdict: bool | None = None
    judged: bool = False
    """A reporter judged the state (its verdict may still be None)."""
    assessment: Assessment | None = None
    wrong_share: float = 0.0
    """Of the movable objects, the share the verdict names wrong (0 when it names none)."""


@dataclass(frozen=True)
class Decision:
    """The rule that fired, whether the loop stops, whether a next attempt resets the scene, and
    whether the next plan is told the reporter's verdict."""

    rule: str
    stop: bool
    reset: bool = True
    shows_report: bool = True

    def __post_init__(self) -> None:
        if self.rule not in LOOP_RULES:
            raise ValueError(f"unknown loop rule {self.rule!r}")


def check_policy(policy: str) -> str:
    if policy not in LOOP_POLICIES:
        raise ConfigError(f"unknown loop policy {policy!r}; valid: {', '.join(LOOP_POLICIES)}")
    return policy


def judges_errors(policy: str) -> bool:
    """Whether a plan that raised after acting is judged (rule a)."""
    return policy == "careful"


def decide(policy: str, outcome: Outcome, *, on_unknown: str = "replan", reset: bool = True) -> Decision:
    """The decision after an attempt under ``policy``; ``reset`` is whether this attempt started
    from the initial scene (a plan not run under ``careful`` keeps a state it did not start from)."""
    careful = check_policy(policy) == "careful"
    if outcome.not_run:
        return Decision("not_run", False, reset=reset or not careful)
    if not outcome.judged:
        return Decision("error", False) if outcome.error else Decision("finished", True)
    a = outcome.assessment
    high = a is not None and a.confidence == "high"
    if outcome.error:
        if careful and outcome.verdict is True and high:
            return Decision("achieved_after_error", True)
        if careful and outcome.verdict is False and high and outcome.wrong_share < 1.0:
            return Decision("partial_replan", False, reset=False)
        return Decision("error", False, shows_report=not careful or high)
    if careful and not high:
        return Decision("low_confidence_stop", True)
    if outcome.verdict is True:
        return Decision("achieved", True)
    if outcome.verdict is None:
        return Decision("unknown_stop", True) if on_unknown == "stop" else Decision("unknown_replan", False)
    if careful and outcome.wrong_share < 1.0:
        return Decision("partial_replan", False, reset=False)
    return Decision("not_achieved", False)


def wrong_share(assessment: Assessment | None, movable: Sequence[int]) -> float:
    """Share of the ``movable`` objects the assessment names wrong."""
    if assessment is None or not movable:
        return 0.0
    return len(set(assessment.wrong_ids) & set(movable)) / len(set(movable))
