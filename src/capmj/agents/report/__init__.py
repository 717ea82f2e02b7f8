"""The reporters: after a plan ran, whether the goal is achieved, and why not.

- :mod:`~capmj.agents.report.registry` — the :class:`Reporter` protocol the closed loop and the
  judge call, and :func:`make_reporter`, which builds a reporter by name from
  :data:`capmj.agents.choices.REPORTER_TABLE`;
- :mod:`~capmj.agents.report.verdict` — what a verdict is (:class:`Report`), the answer it is read
  from (:class:`Answer`, parsed once), the gates an answer passes (:class:`Gate`) and the one loop
  every reporter runs (:func:`ask_for_verdict`: ask, read, gates, one repair, fallback);
- the reporters: :mod:`~capmj.agents.report.text` (``--reporter text``, the ``thesis`` prompt:
  checking code over the scene, with the pre-bound names of :mod:`~capmj.agents.report.text_env`;
  also :func:`plan_check`, the same reporter as the ``parse_completion`` a plan may call),
  :mod:`~capmj.agents.report.checked` (the scene facts as text), :mod:`capmj.agents.report.relations`
  (the goal as calls of pre-bound relation checks) and :mod:`~capmj.agents.report.vlm`
  (``--reporter vlm``: images to a vision-language model);
- :mod:`~capmj.agents.report.confidence` — whether a verdict can be acted on (the ``careful``
  loop's :func:`assess`), its reasons derived from the reporters' gates;
- :mod:`~capmj.agents.report.scene` — the scene measured with the tasks' own rules, as facts and as
  records.

The reporters themselves are imported by :func:`make_reporter` when asked for, not from here.
Nothing here imports the agent, its loop policy or the planner (``tests/test_wings.py``).
"""

from capmj.agents.report.confidence import Assessment, assess
from capmj.agents.report.registry import Reporter, ReporterClass, make_reporter
from capmj.agents.report.text import plan_check
from capmj.agents.report.verdict import SOURCES, Report

__all__ = ["SOURCES", "Assessment", "Report", "Reporter", "ReporterClass", "assess", "make_reporter", "plan_check"]
