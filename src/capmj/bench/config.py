"""One frozen configuration of a bench run: what it runs, how, and what ``--resume`` reloads.

:class:`BenchConfig` is built once from the command line (:meth:`BenchConfig.resolve`) and then
only read: the grid, the workers and ``config.json`` all get it, never the argparse namespace.
Why resume reloads *everything*, execution settings included: a run started with ``--workers 1
--concurrency 1`` against a slow local model must not be resumed at the defaults (2 workers × 4
requests in flight) just because the resume's command line was short.  A setting given again on
the resume's command line wins, and the change is recorded in ``config.json``'s ``resumes`` list
(when, the command line, each changed setting ``{"from": ..., "to": ...}``); ``args`` keeps what
the first part of the run ran with.  The settings the latest part ran with are ``args`` with every
recorded change applied (:func:`effective_args`).

``config.json`` from before this schema (``capmj.bench-config/1``: no ``resumes``, resume times in
``resumed_at``, no ``ray_address``) still resumes: missing settings take their defaults, and the
old resume times become ``resumes`` entries whose changes are unknown.
"""

from __future__ import annotations

import os
import shlex
import time
from dataclasses import dataclass, field, replace
from typing import Any, Iterable, Mapping, Sequence

from capmj.bench.configs import Configuration, merged, with_measured_defaults
from capmj.bench.executor import Execution
from capmj.bench.options import AGENT_OPTIONS, EXECUTION_OPTIONS, LLM_CONCURRENCY
from capmj.bench.seeds import TEST_SEEDS
from capmj.bench.spend import RunBudget
from capmj.bench.worker import AgentSpec
from capmj.errors import ConfigError

SCHEMA = "capmj.bench-config/2"
DEFAULT_TASKS = "benchmark"
DEFAULT_AGENT = "oracle"


@dataclass(frozen=True)
class Given:
    """The settings a command line gave, by name; what it left out is absent (not a default)."""

    tasks: str | None = None
    seeds: str | None = None
    agent: str | None = None
    agent_options: Mapping[str, Any] = field(default_factory=dict)
    execution: Mapping[str, Any] = field(default_factory=dict)
    log: bool | None = None
    log_images: bool | None = None
    max_cost_usd: float | None = None
    max_tokens: int | None = None
    configs: tuple[Configuration, ...] | None = None
    """The ``--configs`` configurations (None: not given)."""


@dataclass(frozen=True)
class BenchConfig:
    """What a run does: the grid's selectors, the agent and its options, how the grid runs, logging
    and the run budget.  ``agent_options`` holds only options that were set (by their agent keyword)."""

    tasks: str
    seeds: str
    agent: str
    agent_options: Mapping[str, Any]
    execution: Execution
    log: bool = True
    log_images: bool = False
    run_budget: RunBudget = field(default_factory=RunBudget)
    configs: tuple[Configuration, ...] = ()
    """The grid's configurations (``--configs``), each with its options merged over ``agent_options``
    (:func:`capmj.bench.configs.merged`); empty: one unnamed configuration, ``agent_options``."""

    def __post_init__(self) -> None:
        unknown = sorted(set(self.agent_options) - set(AGENT_OPTIONS))
        if unknown:
            raise ConfigError(f"unknown agent option(s) {', '.join(unknown)}; known: {', '.join(AGENT_OPTIONS)}")
        object.__setattr__(self, "agent_options", {k: v for k, v in self.agent_options.items() if v is not None})

    @property
    def agent_spec(self) -> AgentSpec:
        """How workers build the agent (``--log-images`` makes it log camera images)."""
        return AgentSpec(self.agent, dict(self.agent_options), self.log_images)

    def agent_specs(self) -> list[tuple[str | None, AgentSpec]]:
        """``(configuration name, how workers build its agent)`` of each configuration of the grid,
        in order; one unnamed one without ``--configs``."""
        if not self.configs:
            return [(None, self.agent_spec)]
        return [(c.name, AgentSpec(self.agent, dict(c.options), self.log_images)) for c in self.configs]

    # .................................................................. config.json
    def to_args(self) -> dict[str, Any]:
        """The ``args`` object of ``config.json``."""
        e = self.execution
        return {"tasks": self.tasks, "seeds": self.seeds, "agent": self.agent, "agent_options": dict(self.agent_options),
                "workers": e.workers, "concurrency": e.concurrency, "max_llm_concurrency": e.max_llm_concurrency,
                "executor": e.executor, "ray_address": e.ray_address, "log": self.log, "log_images": self.log_images,
                "run_budget": self.run_budget.as_dict(),
                **({"configs": [c.as_dict() for c in self.configs]} if self.configs else {})}

    @classmethod
    def from_args(cls, args: Mapping[str, Any]) -> "BenchConfig":
        """A configuration from a ``config.json``'s ``args`` (today's or an older schema's)."""
        agent = args.get("agent") or DEFAULT_AGENT
        options = {k: v for k, v in (args.get("agent_options") or {}).items() if k in AGENT_OPTIONS}
        execution = {k: args[k] for k in EXECUTION_OPTIONS if args.get(k) is not None}
        return cls(args.get("tasks") or DEFAULT_TASKS, args.get("seeds") or TEST_SEEDS, agent, options,
                   _execution(execution, agent), bool(args.get("log", True)), bool(args.get("log_images", False)),
                   RunBudget.resolve(None, None, args.get("run_budget")),
                   tuple(Configuration.from_dict(c) for c in args.get("configs") or ()))

    # .................................................................. from a command line
    @classmethod
    def resolve(cls, given: Given, earlier: "BenchConfig | None" = None) -> "BenchConfig":
        """The command line's settings; what it leaves out comes from ``earlier`` (the run being
        resumed), else from the defaults.  Agent options are reloaded one by one, unless the resume
        names another agent (whose options the earlier ones are not)."""
        agent = given.agent or (earlier.agent if earlier else DEFAULT_AGENT)
        same_agent = earlier is not None and agent == earlier.agent
        options = dict(earlier.agent_options) if same_agent and earlier else {}
        options.update(given.agent_options)
        configs: tuple[Configuration, ...] = ()
        if given.configs is not None:  # each over the shared options; a reporter gets the measured loop
            configs = tuple(replace(c, options=with_measured_defaults(merged(c, options))) for c in given.configs)
        elif same_agent and earlier is not None:  # a resume: what each ran with, the resume's options on top
            configs = tuple(replace(c, options={**c.options, **given.agent_options}) for c in earlier.configs)
        if earlier is None:  # a new run: a reporter gets the measured loop (a resume keeps what it ran with)
            options = with_measured_defaults(options)
        execution = dict(_values(earlier.execution) if earlier else {})
        execution.update(given.execution)
        if earlier is not None and given.log is None and given.log_images is None:
            log, images = earlier.log, earlier.log_images
        else:
            log, images = given.log is not False, bool(given.log_images)
        stored_budget = earlier.run_budget.as_dict() if earlier else None
        return cls(given.tasks or (earlier.tasks if earlier else DEFAULT_TASKS),
                   given.seeds or (earlier.seeds if earlier else TEST_SEEDS), agent, options,
                   _execution(execution, agent), log, images,
                   RunBudget.resolve(given.max_cost_usd, given.max_tokens, stored_budget), configs)


def _values(e: Execution) -> dict[str, Any]:
    return {k: getattr(e, k) for k in EXECUTION_OPTIONS}


def _execution(values: Mapping[str, Any], agent: str) -> Execution:
    """An ``Execution`` from the settings given, defaults for the rest (the concurrency's depends on the agent)."""
    return Execution(
        workers=values["workers"] if values.get("workers") is not None else (os.cpu_count() or 1),
        concurrency=values["concurrency"] if values.get("concurrency") is not None else (
            LLM_CONCURRENCY if agent == "llm" else 1),
        max_llm_concurrency=values.get("max_llm_concurrency"),
        executor=values.get("executor") or "local",
        ray_address=values.get("ray_address"))


def changes(before: Mapping[str, Any], after: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """The settings that differ between two ``args`` objects, flat (``agent_options.model``,
    ``run_budget.max_tokens``), each as ``{"from": ..., "to": ...}``."""
    def flat(d: Mapping[str, Any]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for k, v in d.items():
            if isinstance(v, Mapping):
                out.update({f"{k}.{kk}": vv for kk, vv in v.items()})
            else:
                out[k] = v
        return out

    a, b = flat(before), flat(after)
    return {k: {"from": a.get(k), "to": b.get(k)} for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)}


def _apply(args: Mapping[str, Any], changed: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {k: (dict(v) if isinstance(v, Mapping) else v) for k, v in args.items()}
    for key, change in changed.items():
        head, _, tail = key.partition(".")
        if tail:
            sub = out.setdefault(head, {})
            if change.get("to") is None:
                sub.pop(tail, None)
            else:
                sub[tail] = change["to"]
        else:
            out[head] = change.get("to")
    return out


def resumes(stored: Mapping[str, Any]) -> list[dict[str, Any]]:
    """The ``resumes`` of a stored ``config.json`` (an older one's ``resumed_at`` times as entries
    whose changes are unknown)."""
    if "resumes" in stored:
        return [dict(r) for r in stored.get("resumes") or []]
    return [{"at": t, "changed": None} for t in stored.get("resumed_at") or []]


def effective_args(stored: Mapping[str, Any]) -> dict[str, Any]:
    """The ``args`` the latest part of a stored run ran with: the first part's, every recorded change applied."""
    args = dict(stored.get("args") or {})
    for r in resumes(stored):
        if r.get("changed"):
            args = _apply(args, r["changed"])
    return args


def stored_config(stored: Mapping[str, Any]) -> BenchConfig:
    """The configuration the latest part of a stored run ran with."""
    return BenchConfig.from_args(effective_args(stored))


def now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%S%z")


def config_json(config: BenchConfig, argv: Sequence[str], grid: Mapping[str, Any],
                stored: Mapping[str, Any] | None) -> dict[str, Any]:
    """The ``config.json`` of a run (``stored``: the one of the run being resumed, else None).

    A new run records its settings in ``args``; a resume keeps ``args``, ``argv``, the grid and the
    manifest of the earlier parts and appends one ``resumes`` entry: when, its command line, what
    it changed, and its manifest when that differs."""
    if stored is None:
        return {"schema": SCHEMA, "argv": list(argv), "args": config.to_args(), **grid, "started_at": now(),
                "resumes": []}
    out = {k: v for k, v in stored.items() if k != "resumed_at"}
    entry: dict[str, Any] = {"at": now(), "argv": list(argv),
                             "changed": changes(effective_args(stored), config.to_args())}
    for key in ("tasks", "seeds", "agent", "model", "versions", "manifest", "stamp", "configurations"):
        if key not in grid:
            continue
        if key not in out:
            out[key] = grid[key]
        elif out[key] != grid[key]:
            entry[key] = grid[key]
    out.update(schema=SCHEMA, resumes=resumes(stored) + [entry])
    out.setdefault("args", config.to_args())
    out.setdefault("started_at", entry["at"])
    return out


def reproduce_commands(cfg: Mapping[str, Any]) -> list[str]:
    """The commands that made a run folder, from its ``config.json``: the first part's command
    line, then one per resume (each as given)."""
    cmds = []
    argv: Iterable[str] | None = cfg.get("argv")
    if argv is not None:
        cmds.append(shlex.join(["python", "-m", "capmj.bench", *argv]))
    for r in cfg.get("resumes") or []:
        if r.get("argv"):
            cmds.append(shlex.join(["python", "-m", "capmj.bench", *r["argv"]]))
    return cmds



__all__ = ["BenchConfig", "DEFAULT_AGENT", "DEFAULT_TASKS", "Given", "SCHEMA", "changes", "config_json",
           "effective_args", "reproduce_commands", "resumes", "stored_config"]
