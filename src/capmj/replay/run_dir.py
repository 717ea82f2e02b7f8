"""``python -m capmj.replay RUN_DIR``: the failed episodes of a benchmark run, each with its first
diagnostic (or error) and the command that opens its log."""

from __future__ import annotations

import shlex
import sys
from dataclasses import dataclass
from pathlib import Path
from capmj.records import EpisodeRecord
from capmj.replay.reader import ReplayError


@dataclass(frozen=True)
class FailedEpisode:
    task: str
    seed: int
    agent: str
    model: str | None
    why: str                 # first diagnostic, else the error, else "-"
    rrd: Path | None         # absolute path of the log, None when the run logged nothing


def _why(rec: EpisodeRecord) -> str:
    diags = rec.diagnostics
    if diags:
        return str(diags[0]) + (f" (+{len(diags) - 1} more)" if len(diags) > 1 else "")
    return rec.error or "-"


def failed_episodes(run_dir: str | Path) -> tuple[list[FailedEpisode], int]:
    """The failed episodes recorded in ``RUN_DIR/episodes.jsonl`` (task/seed order) and the number
    of episodes recorded."""
    from capmj.bench.results import EPISODES, read_records

    run = Path(run_dir)
    path = run / EPISODES
    if not path.is_file():
        raise ReplayError(f"{run} is not a benchmark run folder: no {EPISODES} in it "
                          f"(write one with python -m capmj.bench ... --out {run})")
    records, _ = read_records(path)
    out = []
    for r in records:
        if r.success:
            continue
        p = None if not r.rrd else (Path(r.rrd) if Path(r.rrd).is_absolute() else run / r.rrd)
        out.append(FailedEpisode(r.task, r.seed, r.agent, r.model, _why(r), p))
    return sorted(out, key=lambda e: (e.task, e.seed, e.agent, e.model or "")), len(records)


def format_failed(run_dir: str | Path, episodes: list[FailedEpisode], total: int | None = None) -> str:
    py = shlex.quote(sys.executable) if " " in sys.executable else sys.executable
    head = f"{len(episodes)} failed episode(s) in {run_dir}" + (f" (of {total})" if total is not None else "")
    lines = [head]
    for e in episodes:
        who = e.agent + (f" ({e.model})" if e.model else "")
        lines += ["", f"{e.task}  seed {e.seed}  {who}", f"  why:  {e.why}"]
        if e.rrd is None:
            lines.append("  log:  none (the run used --no-log)")
        elif not e.rrd.is_file():
            lines.append(f"  log:  {e.rrd} is missing")
        else:
            lines.append(f"  open: {py} -m capmj.replay {shlex.quote(str(e.rrd))} --open")
    return "\n".join(lines)


__all__ = ["FailedEpisode", "failed_episodes", "format_failed"]
