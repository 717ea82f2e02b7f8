"""``python -m capmj.bench``: run task × seed grids for one agent configuration, and its commands.

Without a command it runs a grid (:mod:`capmj.bench.run`).  The commands, ``report``,
``replay-check``, ``judge`` and ``export``, are argparse subcommands named in :data:`COMMANDS`, a
table of ``"module:function"`` strings imported only when the command runs: the bench names the
judge without importing it, so the judge can use the bench's statistics without a cycle.

Exit codes: 0 the grid ran (whatever the success rate), 2 bad input (unknown task/tag/agent, bad
seed range, unwritable output folder, ...) with a one-line error, 128 + signal number when stopped
(130 Ctrl-C, 143 SIGTERM, 129 SIGHUP; workers are stopped, finished episodes are kept and
``--resume`` continues).  The options that configure a run are defined in
:mod:`capmj.bench.options`, the grid command is :mod:`capmj.bench.run`.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
from pathlib import Path
from typing import Callable, NamedTuple, NoReturn, Sequence, cast

from capmj.bench.anomalies import DEFAULT_THRESHOLD
from capmj.bench.config import DEFAULT_TASKS
from capmj.bench.configs import TIERS
from capmj.bench.options import PERCEPTION, add_agent_flags, budget_flags, execution_flags
from capmj.bench.report import report
from capmj.bench.run import CONFIRM_LLM_EPISODES, EXIT_BUDGET, one_line, prepare_out, run_grid
from capmj.bench.seeds import TEST_SEEDS, parse_seeds
from capmj.errors import CapmjError, ConfigError
from capmj.llm.keys import take_secrets
from capmj.tasks import registry

EPILOG = """\
examples:
  python -m capmj.bench                                   # oracle, all benchmark tasks, 50 test seeds
  python -m capmj.bench --tasks stack-all-blocks-on-a-zone,put-block-into-matching-bowl --seeds 10001:10007:2
  python -m capmj.bench --tasks all --seeds 1,3,5 --workers 2 --out runs/smoke
  python -m capmj.bench --out runs/smoke --resume         # run what a killed run did not finish
  python -m capmj.bench --agent llm --model gpt-4o-mini --reporter vlm --log-images   (see docs/llm.md)
  python -m capmj.bench --list                            # tasks, their plugins, tags, broken plugins
  python -m capmj.bench report runs/oracle runs/llm       # side-by-side success table, paired McNemar test
  python -m capmj.bench report runs/oracle runs/llm --html cmp.html   # the same as one page (docs/bench.md)
  python -m capmj.bench replay-check runs/llm             # re-run from the LLM cache alone, compare
  python -m capmj.bench judge --reporter text --model M --out runs/judge   # score a reporter on labelled states
  python -m capmj.bench export runs/llm --format chat-jsonl --out calls.jsonl   (see docs/export.md)
  python -m capmj.bench export runs/llm --bundle llm-evidence.zip   # the run's evidence in one zip (docs/bench.md)

results: DIR/episodes.jsonl (one line per episode), DIR/summary.{json,md,png}, DIR/config.json,
         DIR/rrd/<task>/<seed>-<agent>.rrd (open with: python -m capmj.replay FILE --open)
"""


class Command(NamedTuple):
    """One command of :data:`COMMANDS`."""

    target: str
    """``module:function`` called with the command's arguments (it parses them and returns the exit code)."""
    about: str
    """One line for ``--help``."""


COMMANDS: dict[str, Command] = {
    "report": Command("capmj.bench.cli:report_main",
                      "rebuild summary tables from result folders (several: side by side, paired McNemar test)"),
    "replay-check": Command("capmj.bench.replay_check:main",
                            "re-run a finished run from the LLM cache alone and compare (docs/failures.md)"),
    "judge": Command("capmj.judge.cli:main", "score a completion reporter on labelled final states (docs/judge.md)"),
    "export": Command("capmj.bench.export:main", "a run's LLM calls as fine-tuning data (docs/export.md), or its "
                                                 "evidence bundle (--bundle OUT.zip, docs/bench.md)"),
}
"""``python -m capmj.bench COMMAND ...``; each parses its own arguments (``COMMAND --help``)."""


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
    cf = p.add_argument_group("configurations: a grid axis (docs/bench.md)")
    cf.add_argument("--configs", default=None, metavar="A,B,...",
                    help="run each named configuration of the agent on the same tasks × seeds into this one folder, "
                         "the first the baseline of the profile's paired comparisons; the shipped tiers: "
                         + ", ".join(c.name for c in TIERS) + " (--list-configs), or your own from --configs-file")
    cf.add_argument("--configs-file", type=Path, default=None, metavar="FILE.toml",
                    help="your own configurations: [configs.NAME] tables of agent options (optionally extends = "
                         "\"TIER\")")
    cf.add_argument("--list-configs", action="store_true", help="list the configurations, their options and "
                    "whether this capmj can run them")
    cf.add_argument("--anomaly-threshold", type=float, default=None, metavar="SHARE",
                    help=f"anomaly share above which the summary's first line warns (default: {DEFAULT_THRESHOLD}); "
                         "anomalies (provider errors after retries, quota, an unanswered server, a crash inside "
                         "capmj) never count as the agent's failures")
    cf.add_argument("--no-probe", action="store_true", help="do not ask the LLM server once before the grid starts "
                    "(by default an unreachable server or a refused key stops the run at once, exit 2)")
    PERCEPTION.add_to(p)
    g = p.add_argument_group("LLM agent options (passed to the agent; see docs/llm.md)")
    add_agent_flags(g)  # --model, --api-base, --temperature, --llm-timeout, ..., then --reporter, --attempts, ...
    g.add_argument("--yes", action="store_true", help=f"start more than {CONFIRM_LLM_EPISODES} LLM episodes "
                   "on the default seeds without asking")
    b = p.add_argument_group("run budget (the whole result folder, resumed runs included; see docs/failures.md)")
    for flag in budget_flags(EXIT_BUDGET):
        flag.add_to(b)
    p.add_argument("--out", type=Path, default=None, metavar="DIR", help="result folder (default: runs/<timestamp>)")
    sc = p.add_argument_group("execution (see docs/scale.md)")
    for flag in execution_flags():
        flag.add_to(sc)
    p.add_argument("--resume", action="store_true",
                   help="continue the run in --out: run only the episodes missing from its episodes.jsonl; every "
                        "setting not given again (tasks, seeds, agent and its options, workers, concurrency, "
                        "logging, budget) is the stored config.json's, and one given again is recorded there")
    logs = p.add_mutually_exclusive_group()
    logs.add_argument("--no-log", action="store_true", help="do not write .rrd episode logs")
    logs.add_argument("--log-images", action="store_true", help="also log camera RGB + depth at every primitive")
    p.add_argument("--list", action="store_true", help="list tasks (plugin, version, tags) and broken plugins")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    commands = p.add_subparsers(dest="command", metavar="COMMAND", title="commands",
                                description="instead of a grid; the options above are the grid's, a command's "
                                            "own come after its name (COMMAND --help)")
    for name, command in COMMANDS.items():
        # the command's parser reads its arguments: here they are taken as they are, options included
        sub = commands.add_parser(name, help=command.about, add_help=False, prefix_chars="\0")
        sub.add_argument("args", nargs=argparse.REMAINDER)
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
    p.add_argument("--allow-version-mismatch", action="store_true",
                   help="compare runs whose task stamps differ (a task's code, the MJCF templates, the prompts or "
                        "capmj's version changed between them); by default report refuses them")
    p.add_argument("--anomaly-threshold", type=float, default=None, metavar="SHARE",
                   help=f"anomaly share above which the summary's first line warns (default: the run's, else "
                        f"{DEFAULT_THRESHOLD})")
    p.add_argument("--html", nargs="?", const="", default=None, type=str, metavar="OUT.html",
                   help="also write one self-contained page (heat map, bars, efficiency, anomalies, failure "
                        "gallery; opens from disk), to OUT.html or report.html in the output folder (or here)")
    return p


# ---------------------------------------------------------------------- commands
def _list_tasks() -> int:
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
            print(f"  {name}: {type(err).__name__}: {one_line(str(err))}")
    else:
        print("broken plugins: none")
    return 0


def _list_configs(path: Path | None) -> int:
    from capmj.bench.configs import listing, load_file

    print(f"configurations (shipped tiers{' and ' + str(path) if path else ''}):")
    for line in listing(TIERS + (load_file(path) if path else ())):
        print(line)
    return 0


def report_main(argv: Sequence[str]) -> int:
    args = build_report_parser().parse_args(list(argv))
    out = args.out if args.out is not None else (args.dirs[0] if len(args.dirs) == 1 else None)
    try:
        if out is not None:
            prepare_out(out)
        summary, md = report(args.dirs, out, allow_version_mismatch=args.allow_version_mismatch,
                             anomaly_threshold=args.anomaly_threshold)
    except ConfigError as exc:
        print(f"capmj-bench report: error: {one_line(str(exc))}", file=sys.stderr)
        return 2
    print(json.dumps(summary, indent=2, sort_keys=True) if args.json else md, end="" if not args.json else "\n")
    for warning in summary.get("warnings") or []:
        print(f"capmj-bench report: warning: {warning}", file=sys.stderr)
    if out is not None:
        print(f"wrote {Path(out) / 'summary.md'}, summary.json, summary.png", file=sys.stderr)
    if args.html is not None:
        from capmj.bench.page import REPORT_HTML, write_page

        page = Path(args.html) if args.html else Path(out if out is not None else ".") / REPORT_HTML
        try:
            print(f"wrote {write_page(page, summary, args.dirs)}", file=sys.stderr)
        except OSError as exc:
            print(f"capmj-bench report: error: cannot write {page}: {one_line(str(exc))}", file=sys.stderr)
            return 2
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """The bench's commands.  Every one starts by taking the secrets out of this process's
    environment (:func:`capmj.llm.keys.take_secrets`): the grid, ``judge`` and ``replay-check`` run
    LLM-written code here and in workers, which inherit the environment; the LLM client gets its
    key explicitly."""
    take_secrets()
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is not None:
        if argv[0] != args.command:
            parser.error(f"the grid's options do not go with a command: python -m capmj.bench {args.command} "
                         "[its options]")
        return command_main(args.command)(args.args)
    try:
        if args.list:
            return _list_tasks()
        if args.list_configs:
            return _list_configs(args.configs_file)
        return run_grid(args, argv)
    except ConfigError as exc:
        print(f"capmj-bench: error: {one_line(str(exc))}", file=sys.stderr)
        return 2


def command_main(name: str) -> Callable[[Sequence[str]], int]:
    """The ``main`` of command ``name`` of :data:`COMMANDS`, imported now."""
    module, _, attr = COMMANDS[name].target.partition(":")
    return cast(Callable[[Sequence[str]], int], getattr(importlib.import_module(module), attr))


__all__ = ["COMMANDS", "EPILOG", "Command", "build_parser", "build_report_parser", "command_main", "main",
           "parse_seeds", "report_main"]


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
