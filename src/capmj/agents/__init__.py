"""Agents: the oracle, reference plans and the LLM planner chain, all acting through an episode context."""
