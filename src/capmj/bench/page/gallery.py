"""The failed episodes of one or several run folders, as the page's failure gallery shows them.

Per failed episode: its configuration label (the report's column), task, seed, failure label and
error, the task's diagnostics, each attempt's (or turn's) plan code, error and feedback — from the
record, or from the episode's transcript when the record holds no code — the final top-down
thumbnail the worker wrote (:mod:`capmj.bench.thumbnail`; None when there is none) and the
episode's ``.rrd`` (None when it was run with ``--no-log`` or the file is gone).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from capmj.bench.report import load_folders
from capmj.bench.results import read_records
from capmj.bench.rundir import RunDir
from capmj.bench.transcripts import read_calls
from capmj.records import EpisodeRecord

__all__ = ["Attempt", "FailedEpisode", "failed_episodes", "replay_command"]


@dataclass(frozen=True)
class Attempt:
    """One attempt (single-turn) or turn (``--interaction multi``) of a failed LLM episode."""

    number: int
    code: str | None
    error: str | None = None
    feedback: str | None = None
    verdict: bool | None = None
    finish: bool | None = None


@dataclass(frozen=True)
class FailedEpisode:
    """What the gallery shows of one failed episode."""

    config: str
    task: str
    seed: int
    failure: str | None
    error: str | None
    goal: str
    progress: float
    diagnostics: tuple[str, ...]
    attempts: tuple[Attempt, ...]
    turns: bool
    """True when the attempts are the turns of a multi-turn episode."""
    thumbnail: bytes | None
    rrd: Path | None
    """The episode's log, absolute; None without one."""
    transcript: Path | None
    """The episode's LLM-call transcript, absolute; None without one."""


def replay_command(rrd: Path) -> str:
    """The command that opens an episode's ``.rrd`` in the rerun viewer (docs/replay.md)."""
    import shlex

    return f"capmj-replay {shlex.quote(str(rrd))} --open"


def _attempts(run: RunDir, rec: EpisodeRecord) -> tuple[Attempt, ...]:
    found = tuple(Attempt(a.attempt, a.code, a.error, a.feedback, a.verdict, a.finish) for a in rec.llm_attempts)
    if any(a.code for a in found) or not rec.transcript:
        return found
    try:  # a record without code (an older line): the planner's answers in the transcript
        calls = read_calls(run.root, rec)
    except (OSError, ValueError):
        return found
    planner = [c for c in calls if str(c.get("purpose", "")).startswith("planner")]
    return tuple(Attempt(int(c.get("attempt") or i), str(c.get("completion") or "")) for i, c in
                 enumerate(planner, start=1))


def _existing(path: Path) -> Path | None:
    return path.resolve() if path.is_file() else None


def failed_episodes(dirs: Sequence[str | Path]) -> list[FailedEpisode]:
    """The failed episodes of ``dirs``, labelled as :func:`capmj.bench.report.load_folders` labels
    them (``load_folders`` lists each folder's records in turn), ordered by configuration, task, seed."""
    records, labels, _ = load_folders(dirs)
    sizes = [len(read_records(RunDir(Path(d)).episodes)[0]) for d in dirs]
    folder_of: list[RunDir] = [RunDir(Path(d)) for d, size in zip(dirs, sizes) for _ in range(size)]
    out: list[FailedEpisode] = []
    for rec, run in zip(records, folder_of):
        if rec.success:
            continue
        thumb = run.root / RunDir.thumb_relpath(rec.task, rec.seed, rec.agent, rec.model, rec.config)
        out.append(FailedEpisode(
            config=labels[id(rec)], task=rec.task, seed=rec.seed, failure=rec.failure, error=rec.error,
            goal=rec.goal, progress=rec.progress, diagnostics=tuple(rec.diagnostics),
            attempts=_attempts(run, rec), turns=rec.llm is not None and rec.llm.interaction == "multi",
            thumbnail=thumb.read_bytes() if thumb.is_file() else None,
            rrd=_existing(run.path(rec.rrd)) if rec.rrd else None,
            transcript=_existing(run.path(rec.transcript)) if rec.transcript else None))
    order = {lab: i for i, lab in enumerate(dict.fromkeys(labels[id(r)] for r in records))}
    out.sort(key=lambda e: (order[e.config], e.task, e.seed))
    return out
