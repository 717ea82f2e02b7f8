"""The LLM agent's configuration as two frozen records, and the one place flat options become them.

An :class:`~capmj.agents.llm_agent.agent.LLMAgent` is configured by what it asks the model
(:class:`~capmj.llm.LLMConfig`: model, server, sampling, timeouts, cache) and how its loop runs
(:class:`LLMAgentOptions`: reporter, attempts, loop policy, prompts, sandbox budgets, episode
limits).  Each record checks its own values when built, so a bad value is a ``ConfigError``
naming the option before any episode starts, not a failure deep inside a worker.

The command line, ``config.json`` and :func:`capmj.agents.factory.make_agent` speak in flat
keyword options (``--attempts 2`` is ``attempts=2``, ``--llm-timeout`` is ``timeout_s``: the
names of :data:`capmj.bench.options.AGENT_OPTIONS`).  :func:`llm_agent_configs` is the one place
that splits such a mapping into the two records (and where ``$CAPMJ_LLM_CACHE`` fills in a missing
cache folder), so an option is a field of a record, never a keyword copied through a constructor.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Callable, Mapping

from capmj.agents.choices import FEEDBACKS, INTERACTIONS, ON_UNKNOWN, POLICIES, REPORTER_PROMPTS, REPORTERS
from capmj.agents.lmp.meter import Price, check_limit, parse_price
from capmj.agents.lmp.session import DEFAULT_EPISODE_MAX_HELPER_CALLS
from capmj.agents.llm_agent.loop_policy import check_policy
from capmj.agents.llm_agent.planner import DEFAULT_PLAN_BUDGET
from capmj.agents.prompt_files import EXAMPLES, PLANNER_PROMPTS
from capmj.agents.sandbox import SandboxBudget
from capmj.errors import ConfigError
from capmj.llm import LLMConfig
from capmj.llm.cache import env_cache_dir

DEFAULT_REPLAN_TEMPERATURE = 0.7
"""Sampling temperature of the first planner request of attempts 2, 3, ... (at 0 a small model
repeated its failed plan byte for byte); retries after an identical answer go hotter
(:func:`capmj.agents.llm_agent.planner.replan_sampling`)."""

DEFAULT_REPLAN_RETRIES = 3
"""Requests after a re-plan answer identical to an earlier attempt's plan, before that plan is
recorded as not re-run (the temperatures and seeds are :func:`capmj.agents.llm_agent.planner.replan_sampling`)."""
MAX_REPLAN_RETRIES = 10
"""Upper bound of ``replan_retries``: each retry is a full planner request."""

DEFAULT_LMP_BUDGET = SandboxBudget(wall_s=30.0, max_api_calls=1000)
"""Budget of one helper LMP's code (parse_obj_name, parse_position, parse_completion)."""

DEFAULT_MAX_TURNS = 8
"""Turns of ``--interaction multi`` or ``--policy tools`` when ``max_turns`` is not given."""

DEFAULT_MODEL = "gpt-4o-mini"
"""The model of an LLM agent built from options that name none."""


def _at_least(name: str, value: Any, convert: Callable[[Any], Any], kind: str, minimum: float) -> Any:
    """``convert(value)``, or a ConfigError naming ``name`` when it is not ``kind`` or below ``minimum``."""
    try:
        out = convert(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be {kind} >= {minimum}, got {value!r}") from None
    if not out >= minimum:  # also rejects NaN
        raise ConfigError(f"{name} must be >= {minimum}, got {out}")
    return out


@dataclass(frozen=True)
class LLMAgentOptions:
    """How the LLM agent's loop runs (everything but the LLM client's own settings).

    Values are checked and normalised when the record is built (``attempts="2"`` becomes 2, a
    ``price`` string ``"IN,OUT"`` a :class:`~capmj.agents.lmp.meter.Price`); a bad one raises
    ``ConfigError``.  Whether ``episode_max_cost_usd`` is usable depends on the model's price, so
    the agent checks that against its ``LLMConfig``."""

    reporter: str = "none"
    """The completion reporter: :data:`capmj.agents.choices.REPORTERS`."""
    attempts: int = 1
    on_unknown: str = "replan"
    """:data:`capmj.agents.choices.ON_UNKNOWN`."""
    loop_policy: str = "thesis"
    """:data:`capmj.agents.choices.LOOP_POLICIES`."""
    reporter_prompt: str = "thesis"
    """The text reporter's prompt: :data:`capmj.agents.choices.REPORTER_PROMPTS`."""
    replan_temperature: float = DEFAULT_REPLAN_TEMPERATURE
    replan_retries: int = DEFAULT_REPLAN_RETRIES
    perception: str = "state"
    """The planner API's source: ``capmj.agents.api.perceived.PERCEPTION_MODES`` (checked by the bench's parser)."""
    api: str = "high"
    """The planner API level (``--api``): ``high`` (pick-and-place) or ``low`` (a robot driver's moves,
    :mod:`capmj.agents.api.low_level`), each with its own planner prompt (:data:`capmj.agents.prompt_files.PLANNER_PROMPTS`)."""
    examples: str = "full"
    """``--examples``: the planner prompt with its few-shot examples (``full``) or without (``none``)."""
    plan_budget: SandboxBudget = DEFAULT_PLAN_BUDGET
    lmp_budget: SandboxBudget = DEFAULT_LMP_BUDGET
    max_fn_depth: int = 3
    prompts_dir: Path | None = None
    """The prompt folder (None: the packaged prompts or ``$CAPMJ_PROMPTS_DIR``)."""
    episode_max_tokens: int | None = None
    episode_max_cost_usd: float | None = None
    episode_max_helper_calls: int | None = DEFAULT_EPISODE_MAX_HELPER_CALLS
    """Helper LMP calls the episode's code may make (:class:`~capmj.agents.lmp.session.HelperCallCap`;
    None: no cap).  Over it the episode ends as over its LLM budget (failure ``budget``)."""
    price: Price | None = None
    """The declared price (USD per million input, output tokens); a string ``"IN,OUT"`` is parsed."""
    interaction: str = "single"
    """:data:`capmj.agents.choices.INTERACTIONS`: ``single`` is the plan-and-report loop above; ``multi``
    runs turns of code with feedback (:mod:`capmj.agents.llm_agent.multiturn`) and takes no reporter and
    one attempt."""
    feedback: str | None = None
    """``multi`` only: :data:`capmj.agents.choices.FEEDBACKS` (None: ``text``)."""
    max_turns: int | None = None
    """``multi`` only: turns before the episode ends without the model's FINISH (None: :data:`DEFAULT_MAX_TURNS`)."""
    describe_model: str | None = None
    """``multi`` with ``feedback="describe"`` only: the model that describes what changed (None: the planner's)."""
    policy: str = "code"
    """:data:`capmj.agents.choices.POLICIES`: ``code`` (the model writes code) or ``tools`` (it calls the API's
    functions as tools, in turns bounded by ``max_turns``: :mod:`capmj.agents.llm_agent.tools`); ``tools``
    takes no reporter and one attempt, with ``single`` or ``multi``."""

    def __post_init__(self) -> None:
        def set_(name: str, value: Any) -> None:
            object.__setattr__(self, name, value)  # normalising a frozen record's own field

        set_("loop_policy", check_policy(self.loop_policy))
        if self.api not in PLANNER_PROMPTS:
            raise ConfigError(f"unknown API level {self.api!r}; valid levels: {', '.join(PLANNER_PROMPTS)}")
        if self.examples not in EXAMPLES:
            raise ConfigError(f"unknown examples choice {self.examples!r}; valid: {', '.join(EXAMPLES)}")
        if self.api != "high" and self.policy == "tools":
            raise ConfigError("--policy tools offers the high-level API's functions as tools; --api low runs with "
                              "--policy code")
        if self.reporter_prompt not in REPORTER_PROMPTS:
            raise ConfigError(f"unknown reporter prompt {self.reporter_prompt!r}; valid: {', '.join(REPORTER_PROMPTS)}")
        if self.reporter_prompt != "thesis" and self.reporter == "vlm":
            raise ConfigError(f"reporter prompt {self.reporter_prompt!r} is a text-reporter prompt; it needs "
                              "--reporter text")
        if self.on_unknown not in ON_UNKNOWN:
            raise ConfigError(f"unknown on_unknown policy {self.on_unknown!r}; valid: {', '.join(ON_UNKNOWN)}")
        set_("replan_temperature", _at_least("replan_temperature", self.replan_temperature, float, "a number", 0))
        r = self.replan_retries
        if isinstance(r, bool) or not isinstance(r, int) or not 0 <= r <= MAX_REPLAN_RETRIES:
            raise ConfigError(f"replan_retries (--replan-retries) must be an integer from 0 to {MAX_REPLAN_RETRIES} "
                              f"(0: never ask again after an identical re-plan), got {r!r}")
        if self.reporter not in REPORTERS:
            raise ConfigError(f"unknown reporter {self.reporter!r}; valid reporters: {', '.join(REPORTERS)}")
        set_("attempts", _at_least("attempts", self.attempts, int, "an integer", 1))
        if self.max_fn_depth < 0:
            raise ConfigError(f"max_fn_depth must be >= 0, got {self.max_fn_depth}")
        set_("max_fn_depth", int(self.max_fn_depth))
        if self.prompts_dir is not None:
            set_("prompts_dir", Path(self.prompts_dir))
        set_("price", parse_price(self.price))
        set_("episode_max_tokens", check_limit(self.episode_max_tokens, "episode_max_tokens", int))
        set_("episode_max_cost_usd", check_limit(self.episode_max_cost_usd, "episode_max_cost_usd", float))
        set_("episode_max_helper_calls", check_limit(self.episode_max_helper_calls, "episode_max_helper_calls", int))
        self._check_interaction(set_)

    def _check_interaction(self, set_: Callable[[str, Any], None]) -> None:
        """``interaction`` and the options only ``multi`` takes; ``multi`` normalises ``feedback`` and
        ``max_turns`` to their defaults, so its records always state them."""
        if self.interaction not in INTERACTIONS:
            raise ConfigError(f"unknown interaction {self.interaction!r}; valid: {', '.join(INTERACTIONS)}")
        if self.policy not in POLICIES:
            raise ConfigError(f"unknown policy {self.policy!r}; valid: {', '.join(POLICIES)}")
        tools = self.policy == "tools"
        if self.interaction == "single":
            given = [n for n in ("feedback", "max_turns", "describe_model") if getattr(self, n) is not None
                     and not (tools and n == "max_turns")]
            if given:
                raise ConfigError(f"{', '.join(given)} need(s) --interaction multi")
            if not tools:
                return
        if self.reporter != "none" or self.attempts != 1:
            form = "--policy tools" if tools else "--interaction multi"
            raise ConfigError(f"{form} takes no --reporter and no --attempts: the model's FINISH ends "
                              "the episode, --max-turns bounds it")
        if self.interaction == "single":
            turns = DEFAULT_MAX_TURNS if self.max_turns is None else self.max_turns
            set_("max_turns", _at_least("max_turns", turns, int, "an integer", 1))
            return
        feedback = "text" if self.feedback is None else self.feedback
        if feedback not in FEEDBACKS:
            raise ConfigError(f"unknown feedback {feedback!r}; valid: {', '.join(FEEDBACKS)}")
        if self.describe_model is not None and feedback != "describe":
            raise ConfigError("describe_model (--describe-model) needs --feedback describe")
        set_("feedback", feedback)
        turns = DEFAULT_MAX_TURNS if self.max_turns is None else self.max_turns
        set_("max_turns", _at_least("max_turns", turns, int, "an integer", 1))


OPTION_FIELDS: tuple[str, ...] = tuple(f.name for f in fields(LLMAgentOptions))
"""The flat option names that go to :class:`LLMAgentOptions`."""

CONFIG_FIELDS: tuple[str, ...] = ("model", "api_base", "api_key", "temperature", "max_tokens", "timeout_s",
                                  "max_retries", "backoff_s", "cache_dir", "cache_only")
"""The flat option names that go to :class:`~capmj.llm.LLMConfig` (its fields that are settings of a
run; ``mock_response`` and ``stream`` are the client's test and transport switches)."""

LLM_AGENT_OPTIONS: tuple[str, ...] = CONFIG_FIELDS + OPTION_FIELDS
"""Every flat option :func:`llm_agent_configs` takes."""

_CONFIG_TYPES: dict[str, Callable[[Any], Any]] = {"temperature": float, "max_tokens": int, "timeout_s": float,
                                                   "max_retries": int, "backoff_s": float, "cache_only": bool}
"""Flat values are converted, so ``temperature=0`` from a command line is the 0.0 a record and a
cache key carry."""


def llm_agent_configs(options: Mapping[str, Any]) -> tuple[LLMConfig, LLMAgentOptions]:
    """Flat keyword options (:data:`LLM_AGENT_OPTIONS`; ``None`` means not given) as the agent's two
    records.  A missing ``model`` is :data:`DEFAULT_MODEL`, a missing ``cache_dir``
    ``$CAPMJ_LLM_CACHE``; an unknown name or a bad value raises ``ConfigError``."""
    given = {k: v for k, v in options.items() if v is not None}
    unknown = sorted(set(given) - set(LLM_AGENT_OPTIONS))
    if unknown:
        raise ConfigError(f"agent 'llm' does not take option(s) {', '.join(unknown)}; "
                          f"it accepts: {', '.join(LLM_AGENT_OPTIONS)}")
    llm: dict[str, Any] = {"model": DEFAULT_MODEL, "cache_dir": env_cache_dir()}
    for k in CONFIG_FIELDS:
        if k == "cache_dir" and k in given:
            llm[k] = Path(given[k]) if given[k] else None  # "" switches the cache off, as no folder
        elif k in given:
            value = given[k]
            try:
                llm[k] = _CONFIG_TYPES[k](value) if k in _CONFIG_TYPES else value
            except (TypeError, ValueError):
                raise ConfigError(f"{k} must be {_CONFIG_TYPES[k].__name__}, got {value!r}") from None
    return LLMConfig(**llm), LLMAgentOptions(**{k: given[k] for k in OPTION_FIELDS if k in given})


__all__ = ["CONFIG_FIELDS", "DEFAULT_LMP_BUDGET", "DEFAULT_MAX_TURNS", "DEFAULT_MODEL", "DEFAULT_REPLAN_RETRIES",
           "DEFAULT_REPLAN_TEMPERATURE", "LLMAgentOptions", "LLM_AGENT_OPTIONS", "MAX_REPLAN_RETRIES",
           "OPTION_FIELDS", "llm_agent_configs"]
