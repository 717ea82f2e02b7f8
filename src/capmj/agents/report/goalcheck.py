"""The ``goalcheck`` text-reporter prompt: the model writes the goal's check before seeing the
result, capmj runs it on the measured final scene and on the scene the robot started from.

* the question lists only the keys acting cannot change (``name``, ``kind``, ``color``, ``size``:
  :data:`capmj.agents.report.scene_records.INVENTORY_KEYS`) under the ``records`` prompt's documentation of
  every key (``prompts/reporter_records.py``, the same file: one description of the records);
* the check runs on the full records of the settled final scene, which gives the verdict;
* it runs again on the records of the start scene, where no task's goal holds.  A check that says
  "achieved" there tests nothing of the state: the answer gets the repair request with that
  fact, and if the repaired check says so again its verdict is kept but doubted
  (``holds_at_start``, low-confidence: the ``careful`` loop does not act on it).  A check that
  *fails* on the start scene is not held against it (``[...][0]`` of the blocks in a zone that is
  empty at the start).
* before that, its code is read (:func:`capmj.agents.report.check_reads.blind_problem`): a check that
  reads none of the keys acting changes, or compares one with a value no record can have
  (``b["inside"] != "zone"``), gives one verdict whatever the scene.  The repair request names the
  fault and the values the key has; still blind after it, the verdict is kept but doubted
  (``blind_check``).

Every state of one episode gets the same question, so with ``--llm-cache`` the model is asked once
per (task, seed), not once per state.  The start scene's records are read from the simulator's
initial state, as ``start_area`` is (:meth:`~capmj.agents.report.records.RecordsReporter.start`
keeps both).  Why each gate exists: ``docs/judge.md``, "Why each gate exists".
"""

from __future__ import annotations

import dataclasses
from typing import Any

from capmj.agents.report.check_reads import blind_problem
from capmj.agents.lmp.session import LMPCall, LMPSession
from capmj.agents.report.records import RecordsReporter
from capmj.agents.report.scene_records import INVENTORY_KEYS, records, records_text
from capmj.agents.report.verdict import CheckRun, rerun_check

__all__ = ["HOLDS_AT_START", "GoalCheckReporter"]

HOLDS_AT_START = ("it says the goal already holds in the scene the robot started from, and no goal holds there: "
                  "the check must compare the measured keys (inside, level, rests_on, area, tilted ...) with the goal")
"""The problem the repair request states when a check says "achieved" of the start scene."""


class GoalCheckReporter(RecordsReporter):
    """``--reporter-prompt goalcheck``: the check from goal + inventory, run on the final and start scene."""

    prompt = "goalcheck"

    def question(self, session: LMPSession, ctx: Any, goal: str) -> str:
        """The scene's inventory (the keys acting cannot change) and the goal."""
        inventory = records_text(self._records(session, ctx), INVENTORY_KEYS)
        return (f"# The objects of this scene. When the check runs, every record also has the measured keys above.\n"
                f"{inventory}\n# goal: {' '.join(goal.split())}")

    def _check(self, session: LMPSession, call: LMPCall, text: str, ctx: Any, goal: str, last: bool) -> CheckRun:
        run = super()._check(session, call, text, ctx, goal, last)
        if run.problem is not None or self._start_state is None:
            return run
        start = records(self._start_state, self._start)
        blind = blind_problem(run.code, (start,))  # the values from the start: the question shows no result
        if blind is not None:
            session.record(call, "blind", blind)
            return dataclasses.replace(run, doubt="blind_check") if last else CheckRun(
                None, problem=blind, code=run.code)
        at_start = rerun_check(session, call, run.code, {"objects": start},
                               f"<{self.prompt_file} {session.attempt}.{call.n} start>", "start scene")
        if at_start.verdict is not True:
            return run
        return dataclasses.replace(run, doubt="holds_at_start") if last else CheckRun(
            None, problem=HOLDS_AT_START, code=run.code)
