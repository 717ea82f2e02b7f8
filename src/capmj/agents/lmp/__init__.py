"""Language model programs: asking an LLM for code and running it in the sandbox.

- :mod:`~capmj.agents.lmp.session` — :class:`LMPSession`: one attempt's LMP calls (prompt file →
  LLM → code → sandbox → value), numbered, recorded and capped (:class:`HelperCallCap`), with the
  helper LMPs plan code may call and ``parse_function`` for functions nobody defined;
- :mod:`~capmj.agents.lmp.codeprep` — the static preparation of LLM-written code before the
  sandbox (benign imports dropped, undefined calls found, reserved names);
- :mod:`~capmj.agents.lmp.meter` — :class:`LLMMeter`: an episode's LLM calls counted, priced and
  stopped at its token and cost limits.

The prompt files the LMPs read are :mod:`capmj.agents.prompt_files`.
"""

from capmj.agents.lmp.meter import LLMMeter, Price, parse_price
from capmj.agents.lmp.session import DEFAULT_EPISODE_MAX_HELPER_CALLS, HelperCallCap, LMPCall, LMPSession, find_llm_error

__all__ = ["DEFAULT_EPISODE_MAX_HELPER_CALLS", "HelperCallCap", "LLMMeter", "LMPCall", "LMPSession", "Price",
           "find_llm_error", "parse_price"]
