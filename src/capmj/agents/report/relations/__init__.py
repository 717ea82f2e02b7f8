"""The ``relations`` reporter (``--reporter text --reporter-prompt relations``): the goal written as
calls of pre-bound relation checks, run by capmj on the final and the start scene.

- :mod:`~capmj.agents.report.relations.reporter` — :class:`RelationsReporter` on the reporters'
  one loop, and its gates as values (what an answer's text leaves out or takes from nowhere, a
  check that holds at the start, calls no scene can pass);
- :mod:`~capmj.agents.report.relations.checks` — the ``require_*`` checks and the environment the
  answer runs in (:func:`relation_env`), over the picks of
  :mod:`~capmj.agents.report.relations.picks` (``blocks(color=...)``, ``zone(...)``).
"""

from capmj.agents.report.relations.checks import relation_env
from capmj.agents.report.relations.reporter import RelationsReporter

__all__ = ["RelationsReporter", "relation_env"]
