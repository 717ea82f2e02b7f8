"""The public task checker (``python -m capmj.tasks check NAME...``): protocol, scenes, goal text,
not solved at reset, do-nothing fails, the oracle solves K seeds, reward agrees with predicate.

A package above ``capmj.agents`` because its checks run the oracle; see :mod:`capmj.taskcheck.checks`.
"""

from capmj.taskcheck.checks import (
    DEFAULT_ACCEPT_RATE,
    DEFAULT_SEEDS,
    CheckConfig,
    IdleAgent,
    check_task,
    goal_text_problems,
)
from capmj.taskcheck.report import CHECKS, CheckResult, Report

__all__ = [
    "CHECKS", "CheckConfig", "CheckResult", "DEFAULT_ACCEPT_RATE", "DEFAULT_SEEDS", "IdleAgent", "Report",
    "check_task", "goal_text_problems",
]
