"""``python -m capmj.bench``: run task × seed grids for one agent configuration, and report.

Exit codes: 0 the grid ran (whatever the success rate), 2 bad input (unknown task/tag/agent, bad
seed range, unwritable output folder, ...) with a one-line error, 128 + signal number when stopped
(130 Ctrl-C, 143 SIGTERM, 129 SIGHUP; workers are stopped, finished episodes are kept and
``--resume`` continues).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, NoReturn, Sequence

from capmj.errors import CapmjError, ConfigError
from capmj.llm.options import add_llm_options, llm_values

if TYPE_CHECKING:  # the bench modules load lazily: importing the CLI stays light
    from capmj.bench.grid import GridStats, Job
    from capmj.bench.spend import BudgetTracker, RunBudget
    from capmj.records import EpisodeRecord

TEST_SEEDS = "10001:10101:2"
"""The test split: the 50 odd seeds from 10001 (CLIPort convention)."""
DEFAULT_TASKS = "benchmark"
LLM_OPTIONS = ("model", "api_base", "reporter", "attempts", "temperature", "on_unknown", "replan_temperature",
               "replan_retries", "timeout_s", "max_tokens", "cache_dir", "cache_only", "episode_max_tokens",
               "episode_max_cost_usd", "price", "perception", "loop_policy", "reporter_prompt")
"""The LLM agent's keyword arguments the command line sets (the shared client options among them,
:data:`capmj.llm.options.LLM_OPTIONS`, by their ``LLMConfig`` field names); ``perception`` is also
the reference agent's."""
CONFIRM_LLM_EPISODES = 100
"""More LLM episodes than this on the default seeds need --seeds or --yes (or a 'y' at the prompt)."""
LLM_CONCURRENCY = 4
"""Default episodes in flight per worker for the LLM agent: it mostly waits on HTTP."""
EXECUTORS = ("local", "ray")
STOP_SIGNALS = ("SIGTERM", "SIGHUP")
"""Signals that stop a run like Ctrl-C does: workers killed, finished episodes kept, resumable."""
EXIT_BUDGET = 3
"""Exit code of a run stopped by --max-cost-usd / --max-tokens (resumable with a higher limit)."""

EPILOG = """\
examples:
  python -m capmj.bench                                   # oracle, all benchmark tasks, 50 test seeds
  python -m capmj.bench --tasks stack-all-blocks-on-a-zone,put-block-into-matching-bowl --seeds 10001:10007:2
  python -m capmj.bench --tasks all --seeds 1,3,5 --workers 2 --out runs/smoke
  python -m capmj.bench --out runs/smoke --resume         # run what a killed run did not finish
  python -m capmj.bench --agent llm --model gpt-4o-mini --reporter vlm --log-images   (see docs/llm.md)
  python -m capmj.bench --list                            # tasks, their plugins, tags, broken plugins
  python -m capmj.bench report runs/oracle runs/llm       # side-by-side success table, paired McNemar test
  python -m capmj.bench replay-check runs/llm             # re-run from the LLM cache alone, compare
  python -m capmj.bench judge --reporter text --model M --out runs/judge   # score a reporter on labelled states
  python -m capmj.bench export runs/llm --format chat-jsonl --out calls.jsonl   (see docs/export.md)

results: DIR/episodes.jsonl (one line per episode), DIR/summary.{json,md,png}, DIR/config.json,
         DIR/rrd/<task>/<seed>-<agent>.rrd (open with: python -m capmj.replay FILE --open)
"""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, exit 2 (argparse prints usage + error)
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="python -m capmj.bench", description="Run a grid of capmj episodes (tasks × seeds) "
                "with one agent, write episodes.jsonl and summary tables.", epilog=EPILOG,
                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--tasks", default=None, metavar="SEL",
                   help=f"comma-separated task names, tags (benchmark, generated, ...) or 'all' (default: {DEFAULT_TASKS})")
    p.add_argument("--seeds", default=None, metavar="SEEDS",
                   help=f"seeds as a list '1,3,5' and/or ranges 'start:stop[:step]' (stop excluded); "
                        f"default: the test split {TEST_SEEDS} (50 odd seeds from 10001)")
    p.add_argument("--agent", default=None, help="agent: oracle (default), reference, llm")
    p.add_argument("--perception", default=None, choices=("state", "rgbd"),
                   help="what the planner API of the reference and llm agents reads: the simulator (state, "
                        "default) or the cameras (rgbd; see docs/perception.md)")
    g = p.add_argument_group("LLM agent options (passed to the agent; see docs/llm.md)")
    add_llm_options(g)  # --model, --api-base, --temperature, --llm-timeout, --llm-max-tokens, --llm-cache
    g.add_argument("--reporter", default=None, choices=("none", "text", "vlm"), help="completion reporter")
    g.add_argument("--attempts", type=int, default=None, metavar="N", help="plan attempts (closed loop)")
    g.add_argument("--on-unknown", dest="on_unknown", default=None, choices=("replan", "stop"),
                   help="what an unknown reporter verdict does (default: replan)")
    g.add_argument("--loop-policy", dest="loop_policy", default=None, choices=("thesis", "careful"),
                   help="what the loop does after an attempt: thesis (default: reset and re-plan after any failure) "
                        "or careful (judge a raising plan's state, re-plan from here on a partial verdict, stop on "
                        "a low-confidence one; docs/llm.md)")
    g.add_argument("--reporter-prompt", dest="reporter_prompt", default=None, choices=("thesis", "checked"),
                   help="the text reporter's prompt: thesis (default: checking code) or checked (capmj binds the "
                        "scene facts; docs/judge.md)")
    g.add_argument("--replan-temperature", dest="replan_temperature", type=float, default=None, metavar="T",
                   help="sampling temperature of the planner in attempts 2, 3, ... (default: 0.7)")
    g.add_argument("--replan-retries", dest="replan_retries", type=int, default=None, metavar="N",
                   help="requests after a re-plan identical to an earlier plan, each hotter, before that plan is "
                        "recorded as not re-run (default: 3)")
    g.add_argument("--cache-only", dest="cache_only", action="store_true", default=None,
                   help="answer only from the cache: a missing entry fails the episode, no live call")
    g.add_argument("--yes", action="store_true", help=f"start more than {CONFIRM_LLM_EPISODES} LLM episodes "
                   "on the default seeds without asking")
    g.add_argument("--episode-max-tokens", dest="episode_max_tokens", type=int, default=None, metavar="N",
                   help="LLM tokens per episode; an episode over it ends with failure 'budget'")
    g.add_argument("--episode-max-cost-usd", dest="episode_max_cost_usd", type=float, default=None, metavar="USD",
                   help="LLM cost per episode (needs a known or declared price)")
    g.add_argument("--price", default=None, metavar="IN,OUT",
                   help="declare the model's price in USD per million input,output tokens (local/unlisted models)")
    b = p.add_argument_group("run budget (the whole result folder, resumed runs included; see docs/failures.md)")
    b.add_argument("--max-cost-usd", dest="max_cost_usd", type=float, default=None, metavar="USD",
                   help=f"stop starting episodes once the run's LLM cost reaches USD (exit {EXIT_BUDGET}; "
                        "--resume with a higher limit continues)")
    b.add_argument("--max-tokens", dest="max_tokens", type=int, default=None, metavar="N",
                   help="stop starting episodes once the run's LLM tokens reach N")
    p.add_argument("--out", type=Path, default=None, metavar="DIR", help="result folder (default: runs/<timestamp>)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help=f"worker processes (default: CPU count = {os.cpu_count()}; 0 = run in this process)")
    sc = p.add_argument_group("scale (see docs/scale.md)")
    sc.add_argument("--concurrency", type=int, default=None, metavar="K",
                    help=f"episodes in flight per worker, so one simulates while others wait on the LLM "
                         f"(default: {LLM_CONCURRENCY} for --agent llm, 1 otherwise)")
    sc.add_argument("--max-llm-concurrency", dest="max_llm_concurrency", type=int, default=None, metavar="N",
                    help="cap on LLM requests in flight across all workers (a provider's concurrency quota)")
    sc.add_argument("--executor", default="local", choices=EXECUTORS,
                    help="local: worker processes on this machine (default); ray: one Ray actor per worker "
                         "on a Ray cluster (pip install 'capmj[ray]')")
    sc.add_argument("--ray-address", dest="ray_address", default=None, metavar="ADDR",
                    help="Ray cluster to join, e.g. 10.0.0.1:6379 (default: start a local Ray)")
    p.add_argument("--resume", action="store_true",
                   help="continue the run in --out: run only the episodes missing from its episodes.jsonl "
                        "(tasks/seeds/agent default to the stored config.json)")
    logs = p.add_mutually_exclusive_group()
    logs.add_argument("--no-log", action="store_true", help="do not write .rrd episode logs")
    logs.add_argument("--log-images", action="store_true", help="also log camera RGB + depth at every primitive")
    p.add_argument("--list", action="store_true", help="list tasks (plugin, version, tags) and broken plugins")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def build_report_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="python -m capmj.bench report",
                description="Rebuild summary tables from one or several result folders (one column per "
                            "(agent, model) configuration of each folder).",
                epilog="examples:\n  python -m capmj.bench report runs/a               # rewrites runs/a/summary.*\n"
                       "  python -m capmj.bench report runs/a runs/b --out runs/a-vs-b",
                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dirs", nargs="+", type=Path, metavar="DIR")
    p.add_argument("--out", type=Path, default=None, metavar="DIR",
                   help="write summary.json/md/png here (default: into DIR when there is one DIR, else print only)")
    p.add_argument("--json", action="store_true", help="print summary JSON instead of Markdown")
    return p


# ---------------------------------------------------------------------- parsing helpers
def parse_seeds(text: str) -> list[int]:
    """``"1,3,5"``, ``"10001:10101:2"`` or a mix ``"1,10:20"``; order kept, repeats dropped."""
    out: list[int] = []
    parts = [p.strip() for p in str(text).split(",")]
    if not any(parts):
        raise ConfigError(f"empty seed list {text!r}; give e.g. 1,3,5 or {TEST_SEEDS}")
    for part in parts:
        if not part:
            raise ConfigError(f"bad seed list {text!r}: empty item; give e.g. 1,3,5 or {TEST_SEEDS}")
        if ":" in part:
            bits = part.split(":")
            if len(bits) not in (2, 3):
                raise ConfigError(f"bad seed range {part!r}: use start:stop[:step], e.g. {TEST_SEEDS}")
            try:
                start, stop = int(bits[0]), int(bits[1])
                step = int(bits[2]) if len(bits) == 3 else 1
            except ValueError:
                raise ConfigError(f"bad seed range {part!r}: start, stop and step must be integers, e.g. {TEST_SEEDS}") from None
            if step <= 0:
                raise ConfigError(f"bad seed range {part!r}: step must be positive")
            if start >= stop:
                raise ConfigError(f"bad seed range {part!r}: it is empty (stop is excluded and must exceed start)")
            if start < 0:
                raise ConfigError(f"bad seed range {part!r}: seeds must be >= 0")
            vals: Sequence[int] = range(start, stop, step)
        else:
            try:
                vals = [int(part)]
            except ValueError:
                raise ConfigError(f"bad seed {part!r}: seeds are integers; give e.g. 1,3,5 or {TEST_SEEDS}") from None
            if vals[0] < 0:
                raise ConfigError(f"bad seed {part!r}: seeds must be >= 0")
        for v in vals:
            if v not in out:
                out.append(v)
    return out


def _one_line(msg: str) -> str:
    return " ".join(str(msg).split())


def _prepare_out(path: Path) -> Path:
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


def _list_tasks() -> int:
    from capmj.tasks import registry

    infos = registry.list_tasks()
    bad = registry.broken(load=True)
    rows = []
    for info in infos:
        if info.name in bad:
            continue
        try:
            tags = ",".join(sorted(registry.tags_of(info.name))) or "-"
        except CapmjError:
            continue
        rows.append((info.name, f"{info.distribution} {info.version}".strip(), tags))
    w0 = max([len(r[0]) for r in rows] + [4])
    w1 = max([len(r[1]) for r in rows] + [6])
    print(f"tasks ({len(rows)}):")
    print(f"  {'name':<{w0}}  {'plugin':<{w1}}  tags")
    for name, dist, tags in rows:
        print(f"  {name:<{w0}}  {dist:<{w1}}  {tags}")
    if registry.plugins_disabled():
        print(f"(entry-point plugins are disabled by {registry.DISABLE_ENV})")
    if bad:
        print(f"broken plugins ({len(bad)}):")
        for name, err in bad.items():
            print(f"  {name}: {type(err).__name__}: {_one_line(str(err))}")
    else:
        print("broken plugins: none")
    return 0


# ---------------------------------------------------------------------- grid command
def _resolve_tasks(selector: str) -> tuple[list[str], list[Any]]:
    """Task names of a selector, each checked to load; plus the hand-registered task objects."""
    from capmj.tasks import registry

    names = registry.resolve(selector)
    registered = []
    infos = {i.name: i for i in registry.list_tasks()}
    for n in names:
        try:
            task = registry.get_task(n)
        except CapmjError as exc:
            raise ConfigError(f"task {n!r} is unusable: {_one_line(str(exc))}") from None
        if n in infos and infos[n].distribution == registry.REGISTERED:
            registered.append(task)
    if not names:
        raise ConfigError(f"task selection {selector!r} matches no usable task")
    return names, registered


def _confirm_llm_grid(args: argparse.Namespace, agent: str, n: int) -> None:
    """Ask before a default-seed LLM grid of more than CONFIRM_LLM_EPISODES episodes starts."""
    if agent != "llm" or n <= CONFIRM_LLM_EPISODES or args.seeds is not None or args.yes or args.resume:
        return
    what = f"this would start {n} LLM episodes on the default test seeds ({TEST_SEEDS})"
    if sys.stdin is not None and sys.stdin.isatty():
        if input(f"capmj-bench: {what}. Continue? [y/N] ").strip().lower() in ("y", "yes"):
            return
    raise ConfigError(f"{what}; give --seeds explicitly (e.g. --seeds 10001:10011:2) or add --yes")


@dataclass
class _Settings:
    """What to run, after ``--resume`` merged the stored config.json under the command line."""

    out: Path
    stored: dict[str, Any] | None
    tasks_sel: str
    seeds_sel: str
    agent_name: str
    options: dict[str, Any]
    workers: int
    concurrency: int
    log: bool
    images: bool
    run_budget: RunBudget


@dataclass
class _Grid:
    """The checked grid: seeds, task names (and hand-registered task objects) and the agent's identity."""

    seeds: list[int]
    tasks: list[str]
    registered: list[Any]
    agent_label: str
    model: str | None
    manifest: dict[str, Any]


def run(args: argparse.Namespace, argv: Sequence[str]) -> int:
    """The grid command: settings (resume merging) → validation → config.json → the episodes still
    to run → running them with progress → summary files → printed results and exit code."""
    settings = _settings(args)
    grid = _validate(args, settings)
    _write_config(args, argv, settings, grid)
    jobs, budget, total = _plan(settings, grid)
    progress = _Progress(budget, len(jobs), show=not args.no_progress)
    stats, interrupted, elapsed = _execute(args, settings, grid, jobs, budget, progress)
    records, summary = _write_summary(settings, stats, elapsed, progress, budget)
    return _print_outcome(settings.out, summary, records, total, elapsed, progress, budget, interrupted)


def _settings(args: argparse.Namespace) -> _Settings:
    """The result folder, what an earlier run left there (``--resume``), and the run's options: the
    command line wins, the stored config.json fills in what it leaves out; numbers are checked."""
    from capmj.bench.results import CONFIG, EPISODES, load_json
    from capmj.bench.spend import RunBudget

    if args.out is None:
        if args.resume:
            raise ConfigError("--resume needs --out DIR (the folder of the run to continue)")
        args.out = Path("runs") / time.strftime("%Y%m%d-%H%M%S")
    out: Path = args.out
    stored = load_json(out / CONFIG) if args.resume else None
    if args.resume and not (out / EPISODES).exists() and stored is None:
        raise ConfigError(f"--resume: {str(out)!r} holds no run to continue (no {EPISODES} or {CONFIG})")
    if not args.resume and (out / EPISODES).exists() and (out / EPISODES).stat().st_size > 0:
        raise ConfigError(f"{str(out)!r} already holds results; add --resume to continue that run or choose another --out")
    prev_args = (stored or {}).get("args") or {}
    tasks_sel = args.tasks or prev_args.get("tasks") or DEFAULT_TASKS
    seeds_sel = args.seeds or prev_args.get("seeds") or TEST_SEEDS
    agent_name = args.agent or prev_args.get("agent") or "oracle"
    shared = llm_values(args)
    options = {k: shared[k] if k in shared else getattr(args, k) for k in LLM_OPTIONS}
    if args.resume and not any(v is not None for v in options.values()) and args.agent is None:
        options.update({k: v for k, v in (prev_args.get("agent_options") or {}).items() if k in LLM_OPTIONS})
    options = {k: v for k, v in options.items() if v is not None}
    workers = (os.cpu_count() or 1) if args.workers is None else args.workers
    if workers < 0:
        raise ConfigError(f"--workers must be >= 0, got {workers}")
    concurrency = args.concurrency if args.concurrency is not None else (
        LLM_CONCURRENCY if agent_name == "llm" else 1)
    if concurrency < 1:
        raise ConfigError(f"--concurrency must be >= 1, got {concurrency}")
    if args.max_llm_concurrency is not None and args.max_llm_concurrency < 1:
        raise ConfigError(f"--max-llm-concurrency must be >= 1, got {args.max_llm_concurrency}")
    if args.executor == "ray" and workers < 1:
        raise ConfigError("--executor ray needs --workers >= 1 (Ray actors)")
    if args.attempts is not None and args.attempts < 1:
        raise ConfigError(f"--attempts must be >= 1, got {args.attempts}")
    log, images = not args.no_log, bool(args.log_images)
    run_budget = RunBudget.resolve(args.max_cost_usd, args.max_tokens, prev_args.get("run_budget"))
    if args.resume and not (args.no_log or args.log_images) and prev_args:
        log, images = bool(prev_args.get("log", True)), bool(prev_args.get("log_images", False))
    return _Settings(out, stored, tasks_sel, seeds_sel, agent_name, options, workers, concurrency, log, images,
                     run_budget)


def _validate(args: argparse.Namespace, s: _Settings) -> _Grid:
    """Seeds, tasks and agent checked (and an LLM grid confirmed) before the folder is touched;
    then the folder is created and proved writable."""
    from capmj.agents.factory import make_agent
    from capmj.bench.manifest import run_manifest

    seeds = parse_seeds(s.seeds_sel)
    tasks, registered = _resolve_tasks(s.tasks_sel)
    agent = make_agent(s.agent_name, **s.options)  # validates name and options; workers build their own
    _confirm_llm_grid(args, s.agent_name, len(tasks) * len(seeds))
    agent_label, model = getattr(agent, "name", s.agent_name), getattr(agent, "model", None)
    s.run_budget.check_price(agent)
    manifest = run_manifest(agent, tasks, s.stored)
    _prepare_out(s.out)
    return _Grid(seeds, tasks, registered, agent_label, model, manifest)


def _write_config(args: argparse.Namespace, argv: Sequence[str], s: _Settings, g: _Grid) -> None:
    """``config.json``: the command line, the resolved settings and grid, versions, start/resume times."""
    from capmj.bench.results import CONFIG, write_result_json

    config = {
        "schema": "capmj.bench-config/1",
        "argv": list(argv),
        "args": {"tasks": s.tasks_sel, "seeds": s.seeds_sel, "agent": s.agent_name, "agent_options": s.options,
                 "workers": s.workers, "concurrency": s.concurrency, "executor": args.executor,
                 "max_llm_concurrency": args.max_llm_concurrency, "log": s.log, "log_images": s.images,
                 "run_budget": s.run_budget.as_dict()},
        "tasks": g.tasks, "seeds": g.seeds, "agent": g.agent_label, "model": g.model,
        "versions": g.manifest["packages"],
        "manifest": g.manifest,
        "started_at": (s.stored or {}).get("started_at") or time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "resumed_at": list((s.stored or {}).get("resumed_at") or []) + ([time.strftime("%Y-%m-%dT%H:%M:%S%z")]
                                                                        if args.resume else []),
    }
    write_result_json(s.out / CONFIG, config)


def _plan(s: _Settings, g: _Grid) -> tuple[list[Job], BudgetTracker, int]:
    """The episodes not yet in episodes.jsonl, the run budget's tracker (counting what is there),
    and the grid's size; prints the plan to stderr."""
    from capmj.bench.grid import Job, rrd_relpath
    from capmj.bench.results import EPISODES, read_records
    from capmj.bench.spend import BudgetTracker

    existing, bad = read_records(s.out / EPISODES)
    done = {r.key for r in existing}
    budget = BudgetTracker(s.run_budget, existing)
    jobs = []
    for t in g.tasks:
        for seed in g.seeds:
            if (t, seed, g.agent_label, g.model) in done:
                continue
            rrd = str((s.out / rrd_relpath(t, seed, g.agent_label, g.model)).resolve()) if s.log else None
            jobs.append(Job(t, seed, rrd))
    total = len(g.tasks) * len(g.seeds)
    print(f"capmj-bench: {len(g.tasks)} task(s) × {len(g.seeds)} seed(s) = {total} episode(s) with agent "
          f"{g.agent_label}" + (f" ({g.model})" if g.model else "") + f"; {total - len(jobs)} already done, "
          f"{len(jobs)} to run on {s.workers} worker(s) × {s.concurrency} in flight; results in {s.out}"
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


def _execute(args: argparse.Namespace, s: _Settings, g: _Grid, jobs: list[Job], budget: BudgetTracker,
             progress: _Progress) -> tuple[GridStats | None, int | None, float]:
    """Run the jobs, appending each result to episodes.jsonl as it comes; Ctrl-C, SIGTERM and
    SIGHUP stop the workers and keep what finished.  Returns (stats or None when stopped, the
    stopping signal or None, wall seconds)."""
    from capmj.bench.grid import AgentSpec, run_jobs_to_file
    from capmj.bench.results import EPISODES, ResultsWriter

    interrupted: int | None = None
    stats: GridStats | None
    t0 = time.perf_counter()
    with ResultsWriter(s.out / EPISODES) as writer, _stop_on_signals():
        try:
            stats = run_jobs_to_file(jobs, AgentSpec(s.agent_name, s.options, s.images), workers=s.workers,
                                     out_dir=s.out, writer=writer, progress=progress, registered=g.registered,
                                     concurrency=s.concurrency, max_llm_concurrency=args.max_llm_concurrency,
                                     executor=args.executor, ray_address=args.ray_address, stop=budget.stop)
        except KeyboardInterrupt as exc:
            interrupted = getattr(exc, "signum", signal.SIGINT)
            stats = None
            _stop_resource_tracker()
        finally:
            progress.close()
    return stats, interrupted, time.perf_counter() - t0


def _write_summary(s: _Settings, stats: GridStats | None, elapsed: float, progress: _Progress,
                   budget: BudgetTracker) -> tuple[list[EpisodeRecord], dict[str, Any]]:
    """summary.json/md/png over every episode in the folder (earlier runs' included), with this
    run's own figures under "run"; returns the records and the summary."""
    from capmj.bench.report import write_summary
    from capmj.bench.results import EPISODES, read_records, summarize

    records, _ = read_records(s.out / EPISODES)
    summary = summarize(records)
    summary["run"] = {"elapsed_s": elapsed, "episodes_run": progress.n, "workers": s.workers,
                      "crashes": getattr(stats, "crashes", 0), "retried_after_crash": getattr(stats, "retried", 0),
                      "stopped_by_budget": budget.reason}
    write_summary(s.out, summary, title=f"capmj benchmark results ({s.out.name})")
    return records, summary


def _print_outcome(out: Path, summary: dict[str, Any], records: list[EpisodeRecord], total: int, elapsed: float,
                   progress: _Progress, budget: BudgetTracker, interrupted: int | None) -> int:
    """Success per configuration on stdout, how to continue a stopped run on stderr; the exit code."""
    from capmj.bench.report import pct_cell
    from capmj.bench.results import EPISODES

    for label, st in summary["overall"].items():
        print(f"{label}: {pct_cell(st)}  ({st['successes']}/{st['n']} episodes, mean progress "
              f"{st['mean_progress'] or 0:.2f}, {st['errors']} with errors)")
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


def _stop_resource_tracker() -> None:
    """End multiprocessing's resource-tracker process now rather than when this process exits.

    The workers are dead by now; the tracker would otherwise outlive them while the summary is
    written, and with it a stopped run's process tree (CI cancels and ``timeout`` wait for it).
    """
    try:
        from multiprocessing import resource_tracker

        stop = getattr(resource_tracker._resource_tracker, "_stop")  # private (not in typeshed), stable since 3.8
        stop()
    except Exception:  # noqa: BLE001 - best effort; the tracker ends with us anyway
        pass


def report_main(argv: Sequence[str]) -> int:
    from capmj.bench.report import report

    args = build_report_parser().parse_args(list(argv))
    out = args.out if args.out is not None else (args.dirs[0] if len(args.dirs) == 1 else None)
    try:
        if out is not None:
            _prepare_out(out)
        summary, md = report(args.dirs, out)
    except ConfigError as exc:
        print(f"capmj-bench report: error: {_one_line(str(exc))}", file=sys.stderr)
        return 2
    print(json.dumps(summary, indent=2, sort_keys=True) if args.json else md, end="" if not args.json else "\n")
    for warning in summary.get("warnings") or []:
        print(f"capmj-bench report: warning: {warning}", file=sys.stderr)
    if out is not None:
        print(f"wrote {Path(out) / 'summary.md'}, summary.json, summary.png", file=sys.stderr)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] == "report":
        return report_main(argv[1:])
    if argv and argv[0] == "replay-check":
        from capmj.bench.replay_check import main as replay_check_main

        return replay_check_main(argv[1:])
    if argv and argv[0] == "judge":
        from capmj.judge.cli import main as judge_main

        return judge_main(argv[1:])
    if argv and argv[0] == "export":
        from capmj.bench.export import main as export_main

        return export_main(argv[1:])
    args = build_parser().parse_args(argv)
    try:
        if args.list:
            return _list_tasks()
        return run(args, argv)
    except ConfigError as exc:
        print(f"capmj-bench: error: {_one_line(str(exc))}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
