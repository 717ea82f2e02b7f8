"""Per-episode LLM call transcripts next to ``episodes.jsonl``.

Every LLM call of an episode (messages sent, completion received, tokens, cost, cache hit; see
:mod:`capmj.agents.llm_meter`) is kept in ``DIR/transcripts/<task>/<seed>-<agent>[-<model>].jsonl``,
one call per line, written atomically by the grid's parent process; the episode's record names
the file in ``transcript`` and keeps only the call count.  Why a side file: the messages of one
episode are tens of kilobytes (hundreds with VLM images) and would make ``episodes.jsonl``
unwieldy for the scripts that read it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping

from capmj.atomic import atomic_write

__all__ = ["read_calls", "transcript_relpath", "write_calls"]


def transcript_relpath(task: str, seed: int, agent: str, model: str | None) -> str:
    from capmj.bench.grid import rrd_relpath

    return "transcripts/" + rrd_relpath(task, seed, agent, model)[len("rrd/"):-len(".rrd")] + ".jsonl"


def write_calls(out_dir: str | Path, rec: dict[str, Any]) -> None:
    """Move ``rec["calls"]`` into the episode's transcript file (``rec["transcript"]`` names it)."""
    calls = rec.pop("calls", None)
    if not calls:
        return
    rel = transcript_relpath(rec["task"], rec["seed"], rec["agent"], rec.get("model"))
    path = Path(out_dir) / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path, encoding="utf-8") as f:
        for call in calls:
            f.write(json.dumps(call, sort_keys=True, ensure_ascii=False) + "\n")
    rec["transcript"] = rel


def read_calls(out_dir: str | Path, rec: Mapping[str, Any]) -> list[dict[str, Any]]:
    """The calls of one episode record ([] for an episode without LLM calls)."""
    rel = rec.get("transcript")
    if not rel:
        return list(rec.get("calls") or [])
    with open(Path(out_dir) / rel, encoding="utf-8") as f:
        return [json.loads(line) for line in f if line.strip()]
