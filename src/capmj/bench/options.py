"""The bench's command-line options that configure a run, each defined once.

Each option is a :class:`Flag`: its spellings, its argparse ``dest`` (which is also the name it has
in the agent's keyword arguments, in :class:`~capmj.bench.executor.Execution` or in
:class:`~capmj.bench.spend.RunBudget`, and in ``config.json``), its type and help.  The parser is
built from these tables and :mod:`capmj.bench.config` reads the parsed values back through them, so
adding an option is one line here, not a name repeated in the parser, the resume logic and the
report.  The LLM client's own flags (``--model``, ``--llm-timeout``...) are shared with the
generator and live in :mod:`capmj.llm.options`.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import dataclass
from typing import Any, Callable

from capmj.agents.choices import (FEEDBACKS, INTERACTIONS, LOOP_POLICIES, ON_UNKNOWN, POLICIES, REPORTER_PROMPTS, REPORTERS,
                                  reporter_prompt_help)
from capmj.agents.lmp.session import DEFAULT_EPISODE_MAX_HELPER_CALLS
from capmj.errors import ConfigError
from capmj.llm.options import LLM_OPTIONS, add_llm_options, llm_values

LLM_CONCURRENCY = 4
"""Default episodes in flight per worker for the LLM agent: it mostly waits on HTTP."""
EXECUTORS = ("local", "ray")


@dataclass(frozen=True)
class Flag:
    """One option of the bench: ``dest`` names the setting it gives (``None`` when not given)."""

    flags: tuple[str, ...]
    dest: str
    help: str
    type: Callable[[str], Any] | None = None
    metavar: str | None = None
    choices: tuple[str, ...] | None = None
    switch: bool = False
    """A flag without a value (``store_true``): True when given, None when not."""

    def add_to(self, group: Any) -> None:
        kw: dict[str, Any] = {"dest": self.dest, "default": None, "help": self.help}
        if self.switch:
            kw["action"] = "store_true"
        else:
            kw.update({k: v for k, v in (("type", self.type), ("metavar", self.metavar), ("choices", self.choices))
                       if v is not None})
        group.add_argument(*self.flags, **kw)


def perception_mode(name: str) -> str:
    """A valid ``--perception`` value (the error lists them: state, rgbd and any plugins)."""
    from capmj.perception.plugins import check_mode

    try:
        return check_mode(name)
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from exc


PERCEPTION = Flag(("--perception",), "perception", "what the planner API of the reference and llm agents reads: the "
                  "simulator (state, default), the cameras (rgbd), or a perceiver plugin by name (capmj.perceivers "
                  "entry points; see docs/perception.md)", perception_mode, "MODE")

AGENT_FLAGS: tuple[Flag, ...] = (
    Flag(("--reporter",), "reporter", "completion reporter; --reporter text runs with the loop policy and prompt "
         "measured never to hurt, careful + relations, unless --loop-policy/--reporter-prompt say otherwise (the "
         "thesis's loop: --configs thesis, or --loop-policy thesis --reporter-prompt thesis; docs/llm.md)",
         choices=REPORTERS),
    Flag(("--attempts",), "attempts", "plan attempts (closed loop)", int, "N"),
    Flag(("--on-unknown",), "on_unknown", "what an unknown reporter verdict does (default: replan)",
         choices=ON_UNKNOWN),
    Flag(("--loop-policy",), "loop_policy", "what the loop does after an attempt: careful (the default with "
         "--reporter text: judge a raising plan's state, re-plan from here on a partial verdict, stop on a "
         "low-confidence one) or thesis (reset and re-plan after any failure: the thesis's loop, the default with "
         "--reporter vlm; docs/llm.md)", choices=LOOP_POLICIES),
    Flag(("--reporter-prompt",), "reporter_prompt", reporter_prompt_help() + " (with --reporter text the bench's "
         "default is relations, the prompt measured never to hurt)", choices=REPORTER_PROMPTS),
    Flag(("--replan-temperature",), "replan_temperature", "sampling temperature of the planner in attempts 2, 3, "
         "... (default: 0.7)", float, "T"),
    Flag(("--replan-retries",), "replan_retries", "requests after a re-plan identical to an earlier plan, each "
         "hotter, before that plan is recorded as not re-run (default: 3)", int, "N"),
    Flag(("--cache-only",), "cache_only", "answer only from the cache: a missing entry fails the episode, no live "
         "call", switch=True),
    Flag(("--episode-max-tokens",), "episode_max_tokens", "LLM tokens per episode; an episode over it ends with "
         "failure 'budget'", int, "N"),
    Flag(("--episode-max-cost-usd",), "episode_max_cost_usd", "LLM cost per episode (needs a known or declared "
         "price)", float, "USD"),
    Flag(("--episode-max-helper-calls",), "episode_max_helper_calls", "helper LMP calls per episode (parse_obj_name, "
         f"parse_position, ... called by the code; default: {DEFAULT_EPISODE_MAX_HELPER_CALLS}); an episode over it "
         "ends with failure 'budget'",
         int, "N"),
    Flag(("--interaction",), "interaction", "single (default: one whole plan per attempt) or multi (turns of code, "
         "each run where the last left the robot, with feedback, until the model answers FINISH; docs/llm.md)",
         choices=INTERACTIONS),
    Flag(("--feedback",), "feedback", "what --interaction multi shows after a turn: text (default: output, error, API "
         "calls, objects), image (also the cameras' RGB views) or describe (also a model's account of what changed)",
         choices=FEEDBACKS),
    Flag(("--max-turns",), "max_turns", "turns of --interaction multi or --policy tools (default: 8); a model that never says FINISH "
         "ends there (failure 'no_finish')", int, "N"),
    Flag(("--describe-model",), "describe_model", "the model of --feedback describe (default: --model)",
         metavar="MODEL"),
    Flag(("--policy",), "policy", "code (default: the model writes Python calling the planner API) or tools (it "
         "calls the API's functions as tools, turn by turn, until it answers without a call or FINISH; with "
         "--interaction single or multi; docs/llm.md)", choices=POLICIES),
    Flag(("--price",), "price", "declare the model's price in USD per million input,output tokens (local/unlisted "
         "models)", metavar="IN,OUT"),
    Flag(("--api",), "api", "the planner API level of the llm and reference agents: high (default: pick-and-place "
         "calls) or low (a robot driver's moves, suction, IK and raw RGB-D images; no pick-and-place; its own prompt; "
         "docs/api_levels.md)", choices=("high", "low")),
    Flag(("--examples",), "examples", "the planner prompt with its few-shot examples (full, default) or without any "
         "(none: the API section unchanged); the reference agent reads no prompt and only records it",
         choices=("full", "none")),
)
"""The LLM agent's own options (after the shared client options of :mod:`capmj.llm.options`); ``api`` and
``examples`` are also the reference agent's."""

AGENT_OPTIONS: tuple[str, ...] = (tuple(o.field for o in LLM_OPTIONS) + tuple(f.dest for f in AGENT_FLAGS)
                                  + (PERCEPTION.dest,))
"""Every agent keyword argument the command line sets (the shared client options by their
``LLMConfig`` field names); ``perception``, ``api`` and ``examples`` are also the reference agent's."""

LABEL_OPTIONS = ("reporter", "attempts", "temperature", "on_unknown", "replan_temperature", "replan_retries",
                 "perception", "loop_policy", "reporter_prompt", "interaction", "feedback", "max_turns", "policy",
                 "api", "examples")
"""Agent options that tell configurations apart in report column labels (besides agent and model)."""


def execution_flags() -> tuple[Flag, ...]:
    """The :class:`~capmj.bench.executor.Execution` options (a function: the help names the CPU count)."""
    return (
        Flag(("--workers",), "workers", f"worker processes (default: CPU count = {os.cpu_count()}; 0 = run in this "
             "process)", int, "N"),
        Flag(("--concurrency",), "concurrency", "episodes in flight per worker, so one simulates while others wait "
             f"on the LLM (default: {LLM_CONCURRENCY} for --agent llm, 1 otherwise)", int, "K"),
        Flag(("--max-llm-concurrency",), "max_llm_concurrency", "cap on LLM requests in flight across all workers "
             "(a provider's concurrency quota)", int, "N"),
        Flag(("--executor",), "executor", "local: worker processes on this machine (default); ray: one Ray actor per "
             "worker on a Ray cluster (pip install 'capmj[ray]')", choices=EXECUTORS),
        Flag(("--ray-address",), "ray_address", "Ray cluster to join, e.g. 10.0.0.1:6379 (default: start a local Ray)",
             metavar="ADDR"),
    )


EXECUTION_OPTIONS = tuple(f.dest for f in execution_flags())
"""The fields of ``Execution``, as the command line names them."""


def budget_flags(exit_budget: int) -> tuple[Flag, ...]:
    """The :class:`~capmj.bench.spend.RunBudget` options."""
    return (
        Flag(("--max-cost-usd",), "max_cost_usd", f"stop starting episodes once the run's LLM cost reaches USD (exit "
             f"{exit_budget}; --resume with a higher limit continues)", float, "USD"),
        Flag(("--max-tokens",), "max_tokens", "stop starting episodes once the run's LLM tokens reach N", int, "N"),
    )


def add_agent_flags(group: Any) -> None:
    """The shared LLM client flags, then the LLM agent's own."""
    add_llm_options(group)
    for f in AGENT_FLAGS:
        f.add_to(group)


def given_agent_options(args: argparse.Namespace) -> dict[str, Any]:
    """The agent options the command line gave (by agent keyword; absent ones left out)."""
    values = llm_values(args) | {f.dest: getattr(args, f.dest) for f in AGENT_FLAGS + (PERCEPTION,)}
    return {k: values[k] for k in AGENT_OPTIONS if values.get(k) is not None}


def given_values(args: argparse.Namespace, names: tuple[str, ...]) -> dict[str, Any]:
    """The settings among ``names`` the command line gave (absent ones left out)."""
    return {n: getattr(args, n) for n in names if getattr(args, n, None) is not None}


__all__ = ["AGENT_FLAGS", "AGENT_OPTIONS", "EXECUTION_OPTIONS", "EXECUTORS", "Flag", "LABEL_OPTIONS",
           "LLM_CONCURRENCY", "PERCEPTION", "add_agent_flags", "budget_flags", "execution_flags",
           "given_agent_options", "given_values"]
