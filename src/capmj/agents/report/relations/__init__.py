"""The ``relations`` reporter (``--reporter text --reporter-prompt relations``): the goal written as
calls of pre-bound relation checks, run by capmj on the final and the start scene.

- :mod:`~capmj.agents.report.relations.reporter` — :class:`RelationsReporter`: ask, run the
  checks, repair once, fall back;
- :mod:`~capmj.agents.report.relations.checks` — the ``require_*`` checks and the environment the
  answer runs in (:func:`relation_env`), over the picks of
  :mod:`~capmj.agents.report.relations.picks` (``blocks(color=...)``, ``zone(...)``);
- :mod:`~capmj.agents.report.relations.coverage` and :mod:`~capmj.agents.report.relations.grounding`
  — what an answer's text leaves out (a relation the goal names) or takes from nowhere (a colour
  or a count the goal does not say).
"""

from capmj.agents.report.relations.checks import relation_env
from capmj.agents.report.relations.reporter import RelationsReporter

__all__ = ["RelationsReporter", "relation_env"]
