"""The layout of a benchmark result folder, owned by one object.

A run folder holds ``episodes.jsonl`` (one line per finished episode), ``config.json`` (what the
run was asked to do, :mod:`capmj.bench.config`), ``summary.{json,md,png}``, one ``.rrd`` log per
episode under ``rrd/<task>/``, one LLM-call transcript per episode under ``transcripts/<task>/``
and one top-down thumbnail per failed episode under ``thumbs/<task>/``.
Why one object: the grid, the transcript writer, the CLI and the readers all need these paths, and
when each built them by hand (one of them by slicing another's string) a change to one silently
broke another.  :class:`RunDir` is the only place a file name of the folder is written.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

EPISODES = "episodes.jsonl"
CONFIG = "config.json"
SUMMARY_JSON = "summary.json"
SUMMARY_MD = "summary.md"
SUMMARY_PNG = "summary.png"
RRD_DIR = "rrd"
TRANSCRIPTS_DIR = "transcripts"
THUMBS_DIR = "thumbs"


def safe_name(s: str) -> str:
    """A file-name-safe spelling of a task, agent or model name (anything odd becomes ``_``)."""
    return "".join(c if c.isalnum() or c in "-_.=" else "_" for c in str(s))


def episode_stem(task: str, seed: int, agent: str, model: str | None, config: str | None = None) -> str:
    """``[<config>/]<task>/<seed>-<agent>[-<model>]``: an episode's file name below ``rrd/`` and
    ``transcripts/`` (``config``: the configuration of a ``--configs`` grid)."""
    head = f"{safe_name(config)}/" if config else ""
    return f"{head}{safe_name(task)}/{seed}-{agent}" + (f"-{safe_name(model)}" if model else "")


@dataclass(frozen=True)
class RunDir:
    """One result folder; ``root`` as given (relative paths stay relative)."""

    root: Path

    def __post_init__(self) -> None:
        object.__setattr__(self, "root", Path(self.root))

    @property
    def episodes(self) -> Path:
        return self.root / EPISODES

    @property
    def config(self) -> Path:
        return self.root / CONFIG

    @property
    def summary_json(self) -> Path:
        return self.root / SUMMARY_JSON

    @property
    def summary_md(self) -> Path:
        return self.root / SUMMARY_MD

    @property
    def summary_png(self) -> Path:
        return self.root / SUMMARY_PNG

    def resolved(self) -> "RunDir":
        """The same folder by its absolute path (workers may run in another directory)."""
        return RunDir(self.root.resolve())

    @staticmethod
    def rrd_relpath(task: str, seed: int, agent: str, model: str | None, config: str | None = None) -> str:
        """``rrd/[<config>/]<task>/<seed>-<agent>[-<model>].rrd``, relative to the folder (what records hold)."""
        return f"{RRD_DIR}/{episode_stem(task, seed, agent, model, config)}.rrd"

    @staticmethod
    def transcript_relpath(task: str, seed: int, agent: str, model: str | None, config: str | None = None) -> str:
        """``transcripts/[<config>/]<task>/<seed>-<agent>[-<model>].jsonl``, relative to the folder."""
        return f"{TRANSCRIPTS_DIR}/{episode_stem(task, seed, agent, model, config)}.jsonl"

    @staticmethod
    def thumb_relpath(task: str, seed: int, agent: str, model: str | None, config: str | None = None) -> str:
        """``thumbs/[<config>/]<task>/<seed>-<agent>[-<model>].png``: a failed episode's final top-down view
        (:mod:`capmj.bench.thumbnail`), relative to the folder."""
        return f"{THUMBS_DIR}/{episode_stem(task, seed, agent, model, config)}.png"

    def thumb(self, task: str, seed: int, agent: str, model: str | None, config: str | None = None) -> Path:
        """The absolute path of an episode's thumbnail (written for failed episodes only)."""
        return (self.root / self.thumb_relpath(task, seed, agent, model, config)).resolve()

    def rrd(self, task: str, seed: int, agent: str, model: str | None, config: str | None = None) -> Path:
        """The absolute path of an episode's ``.rrd`` log."""
        return (self.root / self.rrd_relpath(task, seed, agent, model, config)).resolve()

    def path(self, rel: str) -> Path:
        """A path a record holds (relative to the folder, or absolute from an older run) as a path."""
        p = Path(rel)
        return p if p.is_absolute() else self.root / p

    def relative(self, path: str) -> str:
        """``path`` relative to the folder when it can be (records hold relative paths, so a folder
        can be moved); unchanged when it cannot (another drive)."""
        try:
            return os.path.relpath(path, self.root.resolve())
        except ValueError:
            return path


__all__ = ["CONFIG", "EPISODES", "RRD_DIR", "RunDir", "SUMMARY_JSON", "SUMMARY_MD", "SUMMARY_PNG",
           "THUMBS_DIR", "TRANSCRIPTS_DIR", "episode_stem", "safe_name"]
