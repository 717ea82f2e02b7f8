"""Per-episode LLM call transcripts next to ``episodes.jsonl``.

Every LLM call of an episode (messages sent, completion received, tokens, cost, cache hit; see
:mod:`capmj.agents.lmp.meter`) is kept in ``DIR/transcripts/<task>/<seed>-<agent>[-<model>].jsonl``,
one call per line, written atomically by the grid's parent process; the episode's record names
the file in ``transcript`` and keeps only the call count.  Why a side file: the messages of one
episode are tens of kilobytes (hundreds with VLM images) and would make ``episodes.jsonl``
unwieldy for the scripts that read it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from capmj.atomic import atomic_write
from capmj.bench.rundir import RunDir
from capmj.records import Episode, EpisodeRecord

__all__ = ["read_calls", "write_calls"]


def write_calls(out_dir: str | Path, result: Episode, config: str | None = None) -> str | None:
    """Write ``result.calls`` into the episode's transcript file; its path relative to ``out_dir``
    (what the record's ``transcript`` holds), None for an episode without LLM calls.  ``config``
    names the configuration of a ``--configs`` grid (a folder of its own)."""
    if not result.calls:
        return None
    rel = RunDir.transcript_relpath(result.task, result.seed, result.agent, result.model, config)
    path = RunDir(Path(out_dir)).path(rel)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path, encoding="utf-8") as f:
        for call in result.calls:
            f.write(json.dumps(call, sort_keys=True, ensure_ascii=False) + "\n")
    return rel


def read_calls(out_dir: str | Path, rec: EpisodeRecord) -> list[dict[str, Any]]:
    """The calls of one episode record ([] for an episode without LLM calls)."""
    if not rec.transcript:
        return [dict(c) for c in rec.calls]  # lines written before transcripts held them inline
    with open(RunDir(Path(out_dir)).path(rec.transcript), encoding="utf-8") as f:
        return [json.loads(line) for line in f if line.strip()]
