"""python -m capmj.tasks check NAME... [--seeds K] [--accept-rate R] [--json]

Loads each named task through the registry (names, tags or ``all``), checks it and prints one
report per task (an LLM-written task is first re-checked for confinement, before it is imported); exit code 0 when every task passes, 1 when one fails, 2 for bad input.
"""

from __future__ import annotations

import argparse
import json
import sys

from capmj.errors import CapmjError, PluginError
from capmj.taskcheck.checks import DEFAULT_ACCEPT_RATE, DEFAULT_SEEDS, CheckConfig, check_task
from capmj.taskcheck.report import CheckResult, Report
from capmj.tasks import registry

EPILOG = """examples:
  python -m capmj.tasks check my-task                  # all checks, oracle on seeds 0-4
  python -m capmj.tasks check my-task other-task --seeds 10 --accept-rate 1.0
  python -m capmj.tasks check benchmark --json         # every task tagged 'benchmark', JSON lines
"""


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m capmj.tasks check", description=__doc__, epilog=EPILOG,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="+", metavar="NAME", help="task names, tags or 'all'")
    ap.add_argument("--seeds", type=int, default=DEFAULT_SEEDS, metavar="K",
                    help=f"distinct seeds 0..K-1 to check (default {DEFAULT_SEEDS})")
    ap.add_argument("--accept-rate", type=float, default=DEFAULT_ACCEPT_RATE, metavar="R",
                    help=f"minimum oracle success share (default {DEFAULT_ACCEPT_RATE})")
    ap.add_argument("--json", action="store_true", help="print one JSON report per line instead of text")
    return ap


def _confinement(name: str) -> CheckResult | None:
    """For an LLM-written task, the re-run of its static check and the sha256 of every file before
    anything of it runs (:func:`capmj.confine.manifest.verify`); ``None`` for any other task."""
    problems = registry.confinement(name)
    if problems is None:
        return None
    if problems:
        return CheckResult("confinement", "fail", "not imported: " + "; ".join(problems[:5]))
    return CheckResult("confinement", "pass", "every file unchanged since acceptance, every module passes the static "
                                              "check; it runs only in the jail")


def main(argv: list[str] | None = None) -> int:
    ap = _parser()
    args = ap.parse_args(argv)
    try:
        names = registry.resolve(args.names)
        cfg = CheckConfig.first(args.seeds, accept_rate=args.accept_rate)
    except CapmjError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    ok = True
    for name in names:
        confined = _confinement(name)
        if confined is not None and not confined.passed:
            report = Report(name, (confined,))
        else:
            try:
                report = check_task(registry.get_task(name), CheckConfig(cfg.seeds, cfg.accept_rate, name=name))
            except PluginError as e:
                report = Report(name, (CheckResult("protocol", "error", str(e)),))
            if confined is not None:
                report = Report(name, (confined, *report.results))
        ok &= report.passed
        print(json.dumps(report.to_dict()) if args.json else report.text(), flush=True)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
