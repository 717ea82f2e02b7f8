"""The grid command of ``python -m capmj.bench``: configuration → checks → ``config.json`` → the
episodes still to run → running them → summary files → printed results and the exit code.

The command line is read once, into a frozen :class:`~capmj.bench.config.BenchConfig` (what to run
and how) and an :class:`Invocation` (where, and how to talk to the user); nothing after
:func:`run_grid`'s first line sees the argparse namespace.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, Mapping, Sequence

from capmj.agents.factory import make_agent
from capmj.bench.anomalies import DEFAULT_THRESHOLD, headline
from capmj.bench.config import BenchConfig, Given, config_json, stored_config
from capmj.bench.configs import load_file as load_configs_file
from capmj.bench.configs import resolve as resolve_configs
from capmj.bench.grid import run_jobs_to_file
from capmj.bench.manifest import run_manifest
from capmj.bench.options import EXECUTION_OPTIONS, given_agent_options, given_values
from capmj.bench.pool import stop_resource_tracker
from capmj.bench.probe import probe_agents
from capmj.bench.report import pct_cell, write_summary
from capmj.bench.results import ResultsWriter, load_json, read_records, summarize, write_result_json
from capmj.bench.rundir import EPISODES, RunDir
from capmj.bench.seeds import TEST_SEEDS, parse_seeds
from capmj.bench.spend import BudgetTracker
from capmj.bench.stamp import mismatches, short, task_set_stamp
from capmj.bench.worker import AgentSpec, Job
from capmj.errors import CapmjError, ConfigError
from capmj.tasks import registry

if TYPE_CHECKING:  # names of annotations only
    from capmj.bench.executor import GridStats
    from capmj.records import EpisodeRecord

CONFIRM_LLM_EPISODES = 100
"""More LLM episodes than this on the default seeds need --seeds or --yes (or a 'y' at the prompt)."""
STOP_SIGNALS = ("SIGTERM", "SIGHUP")
"""Signals that stop a run like Ctrl-C does: workers killed, finished episodes kept, resumable."""
EXIT_BUDGET = 3
"""Exit code of a run stopped by --max-cost-usd / --max-tokens (resumable with a higher limit)."""


@dataclass(frozen=True)
class Invocation:
    """What the command line says besides the run's configuration: the folder, resume or not, and
    how to talk to the user."""

    run_dir: RunDir
    resume: bool
    argv: tuple[str, ...]
    seeds_given: bool
    yes: bool
    show_progress: bool
    anomaly_threshold: float = DEFAULT_THRESHOLD
    """Anomaly share above which the summary's first line says so (``--anomaly-threshold``)."""
    probe: bool = True
    """Ask each LLM configuration's server once before the grid starts (``--no-probe``: don't)."""


def read_command_line(args: argparse.Namespace, argv: Sequence[str]) -> tuple[Invocation, Given]:
    """The namespace of :func:`capmj.bench.cli.build_parser`, read once."""
    if args.out is None:
        if args.resume:
            raise ConfigError("--resume needs --out DIR (the folder of the run to continue)")
        out = Path("runs") / time.strftime("%Y%m%d-%H%M%S")
    else:
        out = Path(args.out)
    threshold = getattr(args, "anomaly_threshold", None)
    if threshold is not None and not 0 <= threshold <= 1:
        raise ConfigError(f"--anomaly-threshold must be a share from 0 to 1 (0.1 = 10 %), got {threshold}")
    inv = Invocation(RunDir(out), bool(args.resume), tuple(argv), args.seeds is not None, bool(args.yes),
                     not args.no_progress, DEFAULT_THRESHOLD if threshold is None else threshold,
                     not getattr(args, "no_probe", False))
    configs = None
    names = getattr(args, "configs", None)
    path = getattr(args, "configs_file", None)
    if path is not None and names is None:
        raise ConfigError("--configs-file defines configurations; name the ones to run with --configs A,B,...")
    if names is not None:
        configs = resolve_configs(names, load_configs_file(path) if path is not None else ())
    given = Given(tasks=args.tasks, seeds=args.seeds, agent=args.agent, agent_options=given_agent_options(args),
                  execution=given_values(args, EXECUTION_OPTIONS), log=False if args.no_log else None,
                  log_images=True if args.log_images else None, max_cost_usd=args.max_cost_usd,
                  max_tokens=args.max_tokens, configs=configs)
    return inv, given


@dataclass(frozen=True)
class _Member:
    """One configuration of the grid, checked: its name (None: the run's only, unnamed one), how
    workers build its agent (with the provider's key taken from the environment, if it needs one)
    and the agent's identity."""

    name: str | None
    spec: AgentSpec = field(repr=False)
    agent_label: str
    model: str | None
    agent: Any = field(repr=False, compare=False)
    """The agent built here to check the options (the start-up probe asks its server)."""

    def facts(self) -> dict[str, Any]:
        return {"name": self.name, "agent": self.agent_label, "model": self.model, "options": dict(self.spec.options)}


@dataclass(frozen=True)
class _Grid:
    """The checked grid: seeds, task names (and hand-registered task objects) and its configurations."""

    seeds: list[int]
    tasks: list[str]
    registered: list[Any]
    members: list[_Member]
    manifest: dict[str, Any]
    stamp: dict[str, Any]
    """The task set's version stamp (:mod:`capmj.bench.stamp`)."""

    @property
    def agent_label(self) -> str:
        return self.members[0].agent_label

    @property
    def model(self) -> str | None:
        return self.members[0].model

    def facts(self) -> dict[str, Any]:
        """What ``config.json`` records of the grid (``configurations`` only with ``--configs``)."""
        out = {"tasks": self.tasks, "seeds": self.seeds, "agent": self.agent_label, "model": self.model,
               "versions": self.manifest["packages"], "manifest": self.manifest, "stamp": self.stamp}
        if self.members[0].name is not None:
            out["configurations"] = [m.facts() for m in self.members]
        return out


def run_grid(args: argparse.Namespace, argv: Sequence[str]) -> int:
    """The grid command (see the module docstring)."""
    inv, given = read_command_line(args, argv)
    stored = _stored(inv)
    config = BenchConfig.resolve(given, stored_config(stored) if stored is not None else None)
    grid = _validate(inv, config, stored)
    jobs, budget, total = _plan(inv.run_dir, config, grid)
    if inv.probe:  # the servers of the configurations with episodes to run answer, or the run stops here
        probe_agents(m.agent for m in grid.members if jobs.get(m.name))
    write_result_json(inv.run_dir.config, config_json(config, inv.argv, grid.facts(), stored))
    progress = _Progress(budget, sum(len(j) for j in jobs.values()), show=inv.show_progress)
    stats, interrupted, elapsed = _execute(inv.run_dir, config, grid, jobs, budget, progress)
    records, summary = _write_summary(inv, config, grid, stats, elapsed, progress, budget)
    return _print_outcome(inv.run_dir.root, summary, records, total, elapsed, progress, budget, interrupted)


def _stored(inv: Invocation) -> dict[str, Any] | None:
    """The ``config.json`` of the run ``--resume`` continues (None for a new run); a new run's folder
    must not hold results already."""
    run = inv.run_dir
    if not inv.resume:
        if run.episodes.exists() and run.episodes.stat().st_size > 0:
            raise ConfigError(f"{str(run.root)!r} already holds results; add --resume to continue that run or "
                              "choose another --out")
        return None
    stored = load_json(run.config)
    if not run.episodes.exists() and stored is None:
        raise ConfigError(f"--resume: {str(run.root)!r} holds no run to continue (no {run.episodes.name} or "
                          f"{run.config.name})")
    return stored


def _validate(inv: Invocation, config: BenchConfig, stored: Mapping[str, Any] | None) -> _Grid:
    """Seeds, tasks and agent checked (and an LLM grid confirmed) before the folder is touched;
    then the folder is created and proved writable."""
    if config.agent_options.get("attempts") is not None and config.agent_options["attempts"] < 1:
        raise ConfigError(f"--attempts must be >= 1, got {config.agent_options['attempts']}")
    seeds = parse_seeds(config.seeds)
    tasks, registered = _resolve_tasks(config.tasks)
    agents, members = [], []
    for name, spec in config.agent_specs():
        try:  # validates name and options; workers build their own
            agent = make_agent(config.agent, **spec.options)
        except ConfigError as exc:
            if name is None:
                raise
            raise ConfigError(f"configuration {name!r}: {exc}") from None
        config.run_budget.check_price(agent)
        agents.append(agent)
        members.append(_Member(name, replace(spec, api_key=_environment_key(agent)), getattr(agent, "name", config.agent),
                               getattr(agent, "model", None), agent))
    _confirm_llm_grid(inv, config.agent, len(members) * len(tasks) * len(seeds))
    manifest = run_manifest(agents[0], tasks, stored)
    stamp = run_stamp(agents[0], tasks, stored)
    prepare_out(inv.run_dir.root)
    return _Grid(seeds, tasks, registered, members, manifest, stamp)


PROMPT_READERS = ("llm", "reference")
"""Agents whose episodes depend on the prompt folder (the LLM's prompts, the reference plans)."""


def run_stamp(agent: Any, tasks: Sequence[str], stored: Mapping[str, Any] | None) -> dict[str, Any]:
    """The task set's stamp as this agent runs it (its prompt folder); on a resume, warns (stderr)
    about the tasks whose stamp changed since."""
    from capmj.agents.factory import agent_setting
    from capmj.resources import prompts_dir

    folder = agent_setting(agent, "prompts_dir")
    reads = getattr(agent, "name", "") in PROMPT_READERS
    stamp = task_set_stamp({t: registry.get_task(t) for t in tasks},
                           (Path(folder) if folder else prompts_dir()) if reads else None)
    if stored and stored.get("stamp"):
        for problem in mismatches({"stored run": stored["stamp"], "this resume": stamp}, tasks):
            print(f"capmj-bench: warning: resuming with another task version: {problem}", file=sys.stderr)
    return stamp


def _in_order(records: list[EpisodeRecord], order: Sequence[str]) -> list[EpisodeRecord]:
    """Records with those of the configurations in ``order`` first, in that order (the profile's
    first configuration is its baseline), the others after them as they come."""
    rank = {name: i for i, name in enumerate(order)}
    return sorted(records, key=lambda r: rank.get(r.config, len(rank)) if r.config is not None else len(rank))


def _environment_key(agent: Any) -> str | None:
    """The key an LLM agent's provider reads from the environment (taken out of it when the bench
    started), when its options name no key and no local server: the workers' environment has none."""
    llm = getattr(agent, "config", None)
    if llm is None or getattr(llm, "api_key", None) is not None or getattr(llm, "api_base", None):
        return None
    return getattr(llm, "resolved_api_key", None)


def _resolve_tasks(selector: str) -> tuple[list[str], list[Any]]:
    """Task names of a selector, each checked to load; plus the hand-registered task objects."""
    names = registry.resolve(selector)
    registered = []
    infos = {i.name: i for i in registry.list_tasks()}
    for n in names:
        try:
            task = registry.get_task(n)
        except CapmjError as exc:
            raise ConfigError(f"task {n!r} is unusable: {one_line(str(exc))}") from None
        if n in infos and infos[n].distribution == registry.REGISTERED:
            registered.append(task)
    if not names:
        raise ConfigError(f"task selection {selector!r} matches no usable task")
    return names, registered


def _confirm_llm_grid(inv: Invocation, agent: str, n: int) -> None:
    """Ask before a default-seed LLM grid of more than CONFIRM_LLM_EPISODES episodes starts."""
    if agent != "llm" or n <= CONFIRM_LLM_EPISODES or inv.seeds_given or inv.yes or inv.resume:
        return
    what = f"this would start {n} LLM episodes on the default test seeds ({TEST_SEEDS})"
    if sys.stdin is not None and sys.stdin.isatty():
        if input(f"capmj-bench: {what}. Continue? [y/N] ").strip().lower() in ("y", "yes"):
            return
    raise ConfigError(f"{what}; give --seeds explicitly (e.g. --seeds 10001:10011:2) or add --yes")


def _plan(run: RunDir, config: BenchConfig, g: _Grid) -> tuple[dict[str | None, list[Job]], BudgetTracker, int]:
    """The episodes not yet in episodes.jsonl, per configuration (in grid order), the run budget's
    tracker (counting what is there), and the grid's size; prints the plan to stderr."""
    existing, bad = read_records(run.episodes)
    done = {r.grid_key for r in existing}
    budget = BudgetTracker(config.run_budget, existing)
    jobs: dict[str | None, list[Job]] = {}
    for m in g.members:
        todo = jobs.setdefault(m.name, [])
        for t in g.tasks:
            for seed in g.seeds:
                if (m.name, t, seed, m.agent_label, m.model) in done:
                    continue
                rrd = str(run.rrd(t, seed, m.agent_label, m.model, m.name)) if config.log else None
                todo.append(Job(t, seed, rrd, thumb=str(run.thumb(t, seed, m.agent_label, m.model, m.name))))
    total = len(g.members) * len(g.tasks) * len(g.seeds)
    n_jobs = sum(len(j) for j in jobs.values())
    e = config.execution
    named = [m.name for m in g.members if m.name is not None]
    print("capmj-bench: " + (f"{len(named)} configuration(s) ({', '.join(named)}) × " if named else "")
          + f"{len(g.tasks)} task(s) × {len(g.seeds)} seed(s) = {total} episode(s) with agent "
          f"{g.agent_label}" + (f" ({g.model})" if g.model else "") + f"; {total - n_jobs} already done, "
          f"{n_jobs} to run on {e.workers} worker(s) × {e.concurrency} in flight; results in {run.root}"
          + (f" (skipped {bad} truncated line(s))" if bad else ""),
          file=sys.stderr)
    return jobs, budget, total


class _Progress:
    """Called with every finished episode: feeds the run budget, counts, and moves the progress bar
    (a tqdm bar on stderr, when shown and there is something to run)."""

    def __init__(self, budget: BudgetTracker, n_jobs: int, *, show: bool) -> None:
        self.budget = budget
        self.n = 0
        self.ok = 0
        self.bar: Any = None
        if show and n_jobs:
            from tqdm import tqdm

            self.bar = tqdm(total=n_jobs, file=sys.stderr, unit="ep", dynamic_ncols=True, mininterval=0.5,
                            desc="episodes")

    def __call__(self, rec: EpisodeRecord) -> None:
        self.budget.add(rec)
        self.n += 1
        self.ok += rec.success
        if self.bar is not None:
            self.bar.set_postfix_str(f"success {100 * self.ok / self.n:.0f}% ({self.ok}/{self.n})", refresh=False)
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _execute(run: RunDir, config: BenchConfig, g: _Grid, jobs: Mapping[str | None, list[Job]],
             budget: BudgetTracker, progress: _Progress) -> tuple[GridStats | None, int | None, float]:
    """Run the jobs, one configuration after another, appending each result to episodes.jsonl as
    it comes; Ctrl-C, SIGTERM and SIGHUP stop the workers and keep what finished.  Returns (stats
    or None when stopped, the stopping signal or None, wall seconds)."""
    interrupted: int | None = None
    stats: GridStats | None = None
    t0 = time.perf_counter()
    with ResultsWriter(run.episodes) as writer, _stop_on_signals():
        try:
            for m in g.members:
                if budget.stop():
                    break
                part = run_jobs_to_file(jobs.get(m.name, []), m.spec, config.execution, run_dir=run, writer=writer,
                                        progress=progress, registered=g.registered, stop=budget.stop, config=m.name)
                stats = part if stats is None else _add(stats, part)
        except KeyboardInterrupt as exc:
            interrupted = getattr(exc, "signum", signal.SIGINT)
            stats = None
            stop_resource_tracker()
        finally:
            progress.close()
    return stats, interrupted, time.perf_counter() - t0


def _add(a: GridStats, b: GridStats) -> GridStats:
    """The counts of two parts of a grid (two configurations) together."""
    return replace(a, done=a.done + b.done, successes=a.successes + b.successes, crashes=a.crashes + b.crashes,
                   retried=a.retried + b.retried, episode_wall_s=a.episode_wall_s + b.episode_wall_s,
                   wall_s=a.wall_s + b.wall_s)


def _write_summary(inv: Invocation, config: BenchConfig, g: _Grid, stats: GridStats | None, elapsed: float,
                   progress: _Progress, budget: BudgetTracker) -> tuple[list[EpisodeRecord], dict[str, Any]]:
    """summary.json/md/png over every episode in the folder (earlier runs' included), with this
    run's own figures under "run", the task stamp and each configuration's options; returns the
    records and the summary."""
    run = inv.run_dir
    records, _ = read_records(run.episodes)
    order = [m.name for m in g.members if m.name is not None]
    summary = summarize(_in_order(records, order), anomaly_threshold=inv.anomaly_threshold)
    summary["stamp"] = g.stamp
    for m in g.members:
        if m.name is not None and m.name in summary["configs"]:
            summary["configs"][m.name]["options"] = dict(m.spec.options)
    summary["run"] = {"elapsed_s": elapsed, "episodes_run": progress.n, "workers": config.execution.workers,
                      "crashes": getattr(stats, "crashes", 0), "retried_after_crash": getattr(stats, "retried", 0),
                      "stopped_by_budget": budget.reason}
    write_summary(run.root, summary, title=f"capmj benchmark results ({run.root.name})")
    return records, summary


def _print_outcome(out: Path, summary: dict[str, Any], records: list[EpisodeRecord], total: int, elapsed: float,
                   progress: _Progress, budget: BudgetTracker, interrupted: int | None) -> int:
    """Success per configuration on stdout, how to continue a stopped run on stderr; the exit code."""
    warning = headline(summary.get("anomalies") or {})
    if warning:
        print(warning)
    for label, st in summary["overall"].items():
        print(f"{label}: {pct_cell(st)}  ({st['denominator']}, mean progress "
              f"{st['mean_progress'] or 0:.2f}, {st['errors']} with errors)")
    stamp = summary.get("stamp") or {}
    if stamp:
        print(f"task stamp {short(stamp.get('overall'))} ({len(stamp.get('tasks') or {})} tasks)")
    print(f"ran {progress.n} episode(s) in {elapsed:.1f} s; wrote {out / EPISODES}, {out / 'summary.md'}")
    if interrupted is not None:
        print(f"capmj-bench: interrupted by {signal.Signals(interrupted).name}; continue with: "
              f"python -m capmj.bench --out {out} --resume", file=sys.stderr)
        return 128 + int(interrupted)
    if budget.reason and len(records) < total:
        print(f"capmj-bench: run budget reached: {budget.reason}; {total - len(records)} episode(s) not started. "
              f"Continue with: python -m capmj.bench --out {out} --resume --max-cost-usd/--max-tokens <higher limit>",
              file=sys.stderr)
        return EXIT_BUDGET
    return 0


class Stopped(KeyboardInterrupt):
    """A stop signal (SIGTERM/SIGHUP) delivered to the bench: handled exactly like Ctrl-C."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


@contextlib.contextmanager
def _stop_on_signals() -> Iterator[None]:
    """Turn SIGTERM and SIGHUP into :class:`Stopped` in the main thread while a grid runs.

    Without this a ``kill``, a CI cancel or a closed terminal ends the parent at once and orphans
    its spawn workers (and multiprocessing's resource tracker), which then hold stdout open forever;
    with it the grid's cleanup kills the workers and the folder stays resumable.
    """
    def handler(signum: int, frame: Any) -> None:
        raise Stopped(signum)

    previous = {}
    if threading.current_thread() is threading.main_thread():
        for name in STOP_SIGNALS:
            sig = getattr(signal, name, None)
            if sig is not None:
                previous[sig] = signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)


def one_line(msg: str) -> str:
    return " ".join(str(msg).split())


def prepare_out(path: Path) -> Path:
    """Create the result folder and prove it is writable; ``ConfigError`` otherwise."""
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / f".write-probe-{os.getpid()}"
        with open(probe, "w") as f:
            f.write("ok")
        probe.unlink()
    except OSError as exc:
        raise ConfigError(f"output folder {str(path)!r} is not writable: {exc.strerror or exc}") from None
    return path


__all__ = ["CONFIRM_LLM_EPISODES", "EXIT_BUDGET", "Invocation", "STOP_SIGNALS", "Stopped", "one_line", "prepare_out",
           "read_command_line", "run_grid"]
