"""The LLM agent: plans written by an LLM, run through the planner API, judged, re-planned.

- :mod:`~capmj.agents.llm_agent.agent` — :class:`LLMAgent` and its closed loop (plan, run, judge,
  decide), one attempt record each;
- :mod:`~capmj.agents.llm_agent.planner` — the planner LMP: the request, the feedback of earlier
  attempts, re-plan sampling, running the plan;
- :mod:`~capmj.agents.llm_agent.loop_policy` — what the loop does after an attempt (``thesis``,
  ``careful``): :func:`~capmj.agents.llm_agent.loop_policy.decide`;
- :mod:`~capmj.agents.llm_agent.options` — :class:`LLMAgentOptions`, how the loop runs (besides
  the client's :class:`~capmj.llm.LLMConfig`).

It asks through :mod:`capmj.agents.lmp`, acts through :mod:`capmj.agents.api` and is judged by
:mod:`capmj.agents.report`.
"""

from capmj.agents.llm_agent.agent import LLMAgent
from capmj.agents.llm_agent.options import LLMAgentOptions

__all__ = ["LLMAgent", "LLMAgentOptions"]
