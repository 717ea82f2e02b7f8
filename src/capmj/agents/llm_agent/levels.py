"""The LLM agent's planner at an API level (``--api``) with or without its examples (``--examples``).

:class:`LevelSession` is the LMP session whose ``planner`` prompt is the level's
(:func:`capmj.agents.prompt_files.planner_prompt`: ``prompts/planner.py`` or
``prompts/planner_low.py``, with its few-shot examples or none), and whose helper LMPs never get
the level's actions (the low level's moves and suction, as the high level's pick-and-place).
Everything else is the :class:`~capmj.agents.lmp.session.LMPSession`'s.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from capmj.agents.lmp.session import LMPSession
from capmj.agents.prompt_files import PromptFile, planner_prompt

LOW_LEVEL_ACTIONS = frozenset({"move_to_pose", "move_through", "move_linear", "move_until_contact", "move_to_joints",
                               "home", "suction_on", "suction_off"})
"""The low-level API functions that move the robot: plan code calls them, helper LMPs do not."""


@dataclass
class LevelSession(LMPSession):
    """An LMP session planning at API level :attr:`api` with :attr:`examples` (module docstring)."""

    api_level: str = "high"
    examples: str = "full"

    def prompt(self, name: str) -> PromptFile:
        if name == "planner":
            return planner_prompt(self.api_level, self.examples, self.directory)
        return super().prompt(name)

    def helper_env(self, question: str | None = None) -> dict[str, Any]:
        env = super().helper_env(question)
        return {k: v for k, v in env.items() if k not in LOW_LEVEL_ACTIONS}


__all__ = ["LOW_LEVEL_ACTIONS", "LevelSession"]
