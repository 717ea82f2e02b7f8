"""Digest real generator runs: for every candidate the stage it reached, why it stopped, tokens and
wall time, and the run's stage table (issue #27 item 4).

    python benchmarks/generator_runs.py gen/bu/generation.jsonl gen/td/generation.jsonl > digest.json

Reads only ``generation.jsonl`` (one line per finished candidate, written as each one ends), so it
works on a run that is still going or was killed.  ``stopped_by`` sorts each stop into who is to
blame: ``model`` (its answer failed a check, gave no usable proposal, or the reflection voted
reject), ``capmj`` (an LLM request failed on a live server — timeout, context overflow — or an
answer with a module in it was not parsed), or ``accepted``.  The issue's goal is no ``capmj``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from collections import Counter
from pathlib import Path
from typing import Any

STAGES = ("propose", "examples", "write", "static", "runtime", "reflection", "accepted")
"""The candidate stages in order (``capmj.generate.candidate``); ``package`` = accepted, deduplicated."""

_CAPMJ_FAULTS = ("LLMError", "Timeout", "ContextWindow", "context length")


def stopped_by(rec: dict[str, Any]) -> str:
    """``accepted``, ``capmj`` or ``model`` (see the module docstring)."""
    if rec.get("accepted"):
        return "accepted"
    reason = str(rec.get("reason", ""))
    if any(k in reason for k in _CAPMJ_FAULTS):
        return "capmj"
    return "model"


def failed_check(rec: dict[str, Any]) -> str | None:
    """``stage/check`` of the last failed check, or None."""
    bad = [c for c in rec.get("checks", []) if c.get("outcome") in ("fail", "error")]
    return f"{bad[-1]['stage']}/{bad[-1]['name']}" if bad else None


def digest(path: Path) -> list[dict[str, Any]]:
    rows = []
    for line in path.read_text(encoding="utf-8").splitlines():
        if not line.strip():
            continue
        rec = json.loads(line)
        usage = rec.get("usage", {})
        rows.append({
            "run": str(path.parent.name), "index": rec["index"], "mode": rec["mode"], "name": rec.get("name"),
            "goal": (rec.get("proposal") or {}).get("goal"), "examples": rec.get("examples", []),
            "stage_reached": "accepted" if rec.get("accepted") else rec.get("stage"),
            "stopped_by": stopped_by(rec), "failed_check": failed_check(rec), "repaired": rec.get("repaired"),
            "why": str(rec.get("reason", ""))[:400], "oracle_rate": rec.get("oracle_rate"),
            "calls": usage.get("calls"), "cached_calls": usage.get("cached_calls"),
            "prompt_tokens": usage.get("prompt_tokens"), "completion_tokens": usage.get("completion_tokens"),
            "wall_s": (rec.get("wall_s") or {}).get("total"),
        })
    return sorted(rows, key=lambda r: (r["run"], r["index"]))


def stage_table(rows: list[dict[str, Any]]) -> dict[str, int]:
    """How many candidates reached each stage (a candidate that reached ``runtime`` also reached ``static``)."""
    order = {s: i for i, s in enumerate(STAGES)}
    reached = [order.get(r["stage_reached"], len(STAGES)) for r in rows]
    return {s: sum(1 for k in reached if k >= i) for i, s in enumerate(STAGES)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("journals", nargs="+", type=Path, metavar="generation.jsonl")
    args = ap.parse_args(argv)
    missing = [str(p) for p in args.journals if not p.is_file()]
    if missing:
        print(f"error: no such file: {', '.join(missing)}", file=sys.stderr)
        return 2
    rows = [r for p in args.journals for r in digest(p)]
    walls = sorted(r["wall_s"] for r in rows if r["wall_s"] is not None)
    out = {
        "candidates": len(rows),
        "reached": stage_table(rows),
        "stopped_by": dict(Counter(r["stopped_by"] for r in rows)),
        "failed_checks": dict(Counter(r["failed_check"] for r in rows if r["failed_check"])),
        "wall_s_per_candidate": {"median": statistics.median_high(walls) if walls else None,
                                 "max": walls[-1] if walls else None},
        "rows": rows,
    }
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
