"""Benchmark grids: ``python -m capmj.bench`` (see :mod:`capmj.bench.cli` and docs/bench.md).

Importing this package imports neither rerun nor litellm nor MuJoCo; workers import what they need.
"""

from capmj.bench.cli import main, parse_seeds
from capmj.bench.executor import Execution, Executor
from capmj.bench.grid import LocalExecutor, run_jobs_to_file
from capmj.bench.report import markdown, plot, report, write_summary
from capmj.bench.results import ResultsWriter, read_results, stats, summarize, wilson
from capmj.bench.rundir import RunDir
from capmj.bench.worker import AgentSpec, Job

__all__ = [
    "AgentSpec", "Execution", "Executor", "Job", "LocalExecutor", "ResultsWriter", "RunDir", "main", "markdown",
    "parse_seeds", "plot", "read_results", "report", "run_jobs_to_file", "stats", "summarize", "wilson",
    "write_summary",
]
