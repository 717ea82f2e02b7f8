"""The reporters: after a plan ran, whether the goal is achieved, and why not.

- :mod:`~capmj.agents.report.registry` — the :class:`Reporter` protocol the closed loop and the
  judge call, and :func:`make_reporter`, which builds a reporter by name from
  :data:`capmj.agents.choices.REPORTER_TABLE`;
- the reporters: :mod:`~capmj.agents.report.text` (``--reporter text``, the ``thesis`` prompt:
  checking code over the scene, with the pre-bound names of :mod:`~capmj.agents.report.text_env`),
  :mod:`~capmj.agents.report.checked` (the scene facts as text), :mod:`~capmj.agents.report.records`
  (the facts as records for checking code), :mod:`~capmj.agents.report.goalcheck` (a check
  written from the goal, read by :mod:`~capmj.agents.report.check_reads`),
  :mod:`capmj.agents.report.relations` (the goal as calls of pre-bound relation checks) and
  :mod:`~capmj.agents.report.vlm` (``--reporter vlm``: images to a vision-language model);
- :mod:`~capmj.agents.report.verdict` — what a verdict is (:class:`Report`), how it is read from
  an answer and the ways of asking for one the reporters share;
- :mod:`~capmj.agents.report.confidence` — whether a verdict can be acted on (the ``careful``
  loop's :func:`assess`);
- :mod:`~capmj.agents.report.scene_facts`, :mod:`~capmj.agents.report.scene_records` — the scene
  measured with the tasks' own rules, as text and as records;
- :mod:`~capmj.agents.report.plan_check` — the text reporter as the ``parse_completion`` a plan
  may call.

The reporters themselves are imported by :func:`make_reporter` when asked for, not from here.
Nothing here imports the agent, its loop policy or the planner (``tests/test_wings.py``).
"""

from capmj.agents.report.confidence import Assessment, assess
from capmj.agents.report.plan_check import plan_check
from capmj.agents.report.registry import Reporter, ReporterClass, make_reporter
from capmj.agents.report.verdict import SOURCES, Report

__all__ = ["SOURCES", "Assessment", "Report", "Reporter", "ReporterClass", "assess", "make_reporter", "plan_check"]
