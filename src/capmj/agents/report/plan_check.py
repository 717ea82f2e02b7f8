"""CapRavens' ``parse_completion`` called from inside a plan: the text reporter as a function.

CapRavens' planner examples check their own work before they end: ``if not
parse_completion('<goal>', f'object_positions = {get_obj_pos_dict()}'):`` then ``reset()`` and
a second try.  There ``parse_completion`` was one LMP bound for every program (its
``setup_LMP``), returning the ``judge`` its checking code set.  :func:`plan_check` gives a plan
the same: it lets the world come to rest, as before any verdict, runs capmj's text reporter
(:class:`~capmj.agents.report.text.TextReporter`: checking code, one repair, the direct verdict) on
the scene as it is now, and returns the verdict as a bool.

Why these choices:

* ``context`` is accepted and not needed.  The original passed the poses the plan had just read;
  the reporter's code reads the same live poses (``object_positions`` is pre-bound,
  :mod:`capmj.agents.report.text_env`), so nothing the plan could pass is newer.
* An unknown verdict (no answer gave a bool) returns False: the goal is not known to be achieved,
  so the plan's retry branch runs, as on a False.
* Every LMP call it makes is in the session's transcript and the episode's log like the
  benchmark's own check; its verdict never stands in for the one the agent asks for after the
  plan, which judges the final scene.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from capmj.agents.base import JUDGE_SETTLE_STEPS
from capmj.agents.lmp.session import LMPSession
from capmj.agents.report.text import TextReporter

__all__ = ["plan_check"]


def plan_check(session: LMPSession, ctx: Any) -> Callable[..., bool]:
    """The ``parse_completion(goal, context=None)`` function of one attempt's plan."""
    reporter = TextReporter()
    count = 0

    def parse_completion(goal: Any, context: Any = None) -> bool:
        """Whether ``goal`` is achieved in the scene as it is now (the text reporter's verdict)."""
        nonlocal count
        session.helper_cap.take("parse_completion")
        count += 1
        ctx.world.settle(max_steps=JUDGE_SETTLE_STEPS)
        report = reporter.judge(session, ctx, str(goal))
        verdict = report.verdict is True
        session.recorder.text(f"llm/attempt{session.attempt}/plan_check/{count}",
                              f"goal: {' '.join(str(goal).split())}\nverdict: {report.verdict!r} "
                              f"(from {report.source}) -> {verdict}\nreason: {report.reason}", ctx.world.time)
        return verdict

    return parse_completion
