"""What the task checker answers: one :class:`CheckResult` per check, gathered in a :class:`Report`.

Results are frozen, JSON-friendly data so the same facts can be printed for a plugin author and
stored in ``generation.jsonl`` without a second representation.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Literal, Mapping

Outcome = Literal["pass", "fail", "skip", "error"]

CHECKS: tuple[str, ...] = (
    "protocol", "scenes", "goal_text", "not_solved_at_reset", "do_nothing_fails", "oracle_solves",
    "reward_agrees",
)
"""Every runtime check, in the order they run; a check runs only when all before it passed."""


@dataclass(frozen=True)
class CheckResult:
    """One check's outcome.  ``detail`` says why in one line; ``data`` holds its figures
    (e.g. the oracle's ``rate`` and per-seed results)."""

    name: str
    outcome: Outcome
    detail: str = ""
    wall_s: float = 0.0
    data: Mapping[str, Any] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return self.outcome == "pass"

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["data"] = dict(self.data)
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "CheckResult":
        return cls(str(d["name"]), d["outcome"], str(d.get("detail", "")), float(d.get("wall_s", 0.0)),
                   dict(d.get("data") or {}))


@dataclass(frozen=True)
class Report:
    """All checks of one task, in order; ``passed`` when every check passed."""

    task: str
    results: tuple[CheckResult, ...]

    @property
    def passed(self) -> bool:
        return bool(self.results) and all(r.passed for r in self.results)

    @property
    def first_failure(self) -> CheckResult | None:
        return next((r for r in self.results if r.outcome in ("fail", "error")), None)

    def result(self, name: str) -> CheckResult | None:
        return next((r for r in self.results if r.name == name), None)

    def to_dict(self) -> dict[str, Any]:
        return {"task": self.task, "passed": self.passed, "checks": [r.to_dict() for r in self.results]}

    def text(self) -> str:
        """A human-readable report: one line per check, then the verdict."""
        width = max((len(r.name) for r in self.results), default=0)
        lines = [f"task {self.task}"]
        for r in self.results:
            mark = {"pass": "PASS", "fail": "FAIL", "skip": "skip", "error": "ERROR"}[r.outcome]
            lines.append(f"  {mark:5} {r.name:{width}}  {r.detail}".rstrip())
        bad = self.first_failure
        lines.append("  => OK" if self.passed else f"  => NOT OK: {bad.name if bad else 'no checks ran'}")
        return "\n".join(lines)


__all__ = ["CHECKS", "CheckResult", "Outcome", "Report"]
