"""Agents: the oracle, reference plans and the LLM agent, all acting through an episode context.

The top level holds what every agent shares (:mod:`~capmj.agents.base`, :mod:`~capmj.agents.factory`,
:mod:`~capmj.agents.choices`, :mod:`~capmj.agents.prompt_files`, :mod:`~capmj.agents.attribution`) and
the agents without an LLM (:mod:`~capmj.agents.oracle`, :mod:`~capmj.agents.reference`).  The rest
is in wings, each importing only those before it: :mod:`~capmj.agents.sandbox` (running untrusted
code), :mod:`~capmj.agents.api` (the planner API), :mod:`~capmj.agents.lmp` (asking an LLM for
code), :mod:`~capmj.agents.report` (the reporters) and :mod:`~capmj.agents.llm_agent` (the LLM
agent).
"""
