"""The names the LLM agent's loop options take, in one import-light module.

The command line (:mod:`capmj.bench.options`, whose ``choices`` make argparse name the valid
values), the agent's option record (:mod:`capmj.agents.llm_options`) and the modules that give the
names their meaning (:mod:`capmj.agents.reporter`, :mod:`capmj.agents.loop_policy`) all read these
tuples.  They live here, with no imports, so the bench's parser does not import the reporters (and
litellm's neighbours) to build its help, and a new reporter prompt is added in one place.
"""

from __future__ import annotations

__all__ = ["LOOP_POLICIES", "ON_UNKNOWN", "REPORTERS", "REPORTER_PROMPTS"]

REPORTERS = ("none", "text", "vlm")
"""``--reporter``: no reporter, :class:`~capmj.agents.reporter.TextReporter` (and its prompts) or
:class:`~capmj.agents.reporter_vlm.VLMReporter`."""

REPORTER_PROMPTS = ("thesis", "checked", "records", "goalcheck", "relations")
"""``--reporter-prompt``: :class:`~capmj.agents.reporter.TextReporter`,
:class:`~capmj.agents.reporter_checked.CheckedReporter`,
:class:`~capmj.agents.reporter_records.RecordsReporter`,
:class:`~capmj.agents.reporter_goalcheck.GoalCheckReporter` or
:class:`~capmj.agents.reporter_relations.RelationsReporter`."""

LOOP_POLICIES = ("thesis", "careful")
"""``--loop-policy``: see :mod:`capmj.agents.loop_policy`."""

ON_UNKNOWN = ("replan", "stop")
"""``--on-unknown``: what an unknown reporter verdict does: re-plan like a False verdict (default),
or stop."""
