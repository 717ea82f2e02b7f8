"""``python -m capmj.bench replay-check DIR``: re-run a finished run from the LLM cache alone.

Every episode of ``DIR/episodes.jsonl`` is run again in this process with the run's own agent
options (``config.json``), its LLM client in *cache-only* mode: a completion missing from the cache
is an error of that episode, never a live call, so the check makes zero HTTP calls.  An episode
passes when its final object poses match the recorded ones within ``--tol`` (default 1e-9, per
coordinate and quaternion component), and success, progress, failure label and every attempt's
reporter verdict are the same.  Exit 0 all passed, 1 some differ, 2 bad input.

Why: a published number is only as good as one's ability to reproduce it; physics is deterministic
and the cache holds every completion, so a replay must be *exact*.  A replay that differs points at
an edited cache, changed code or prompts (see the run manifest), or nondeterminism in LLM code.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, Sequence

from capmj.agents.factory import make_agent
from capmj.bench.migrate import as_record
from capmj.bench.config import effective_args
from capmj.bench.results import CONFIG, EPISODES, load_json, read_records, sanitize
from capmj.errors import CapmjError, ConfigError
from capmj.records import EpisodeRecord, EpisodeResult
from capmj.tasks.registry import get_task

__all__ = ["compare", "main", "replay_check"]

TOL = 1e-9


def compare(old: EpisodeRecord, new: EpisodeRecord, tol: float = TOL) -> list[str]:
    """Why the replayed record ``new`` differs from the recorded ``old`` ([] when it does not)."""
    reasons: list[str] = []
    error = new.error or ""
    if "cache-only" in error:
        return [f"missing cache entry: {error}"]
    a, b = old.final_poses, new.final_poses
    if not a:
        reasons.append("the recorded episode has no final poses (written by an older capmj)")
    elif set(a) != set(b):
        reasons.append(f"different objects: {sorted(set(a) ^ set(b))}")
    else:
        worst = max((abs(float(x) - float(y)), name) for name in a for x, y in zip(a[name], b[name]))
        if worst[0] > tol:
            reasons.append(f"final pose of {worst[1]!r} differs by {worst[0]:.3g} (> {tol:g})")
    for key, was, now in (("success", old.success, new.success), ("progress", old.progress, new.progress),
                          ("failure", old.failure, new.failure), ("error", old.error, new.error)):
        if was != now:
            reasons.append(f"{key}: recorded {was!r}, replayed {now!r}")
    va = [x.verdict for x in old.llm_attempts]
    vb = [x.verdict for x in new.llm_attempts]
    if va != vb:
        reasons.append(f"reporter verdicts: recorded {va}, replayed {vb}")
    return reasons


def replay_check(run_dir: str | Path, *, cache_dir: str | Path | None = None, tol: float = TOL,
                 progress: Any = None) -> dict[str, Any]:
    """Replay every episode of ``run_dir``; ``{"episodes", "passed", "http_calls", "mismatches"}``."""
    from capmj.runner import run_episode

    run_dir = Path(run_dir)
    config = load_json(run_dir / CONFIG)
    if config is None or not (run_dir / EPISODES).is_file():
        raise ConfigError(f"{run_dir} is not a result folder (needs {CONFIG} and {EPISODES})")
    args = effective_args(config)  # the settings the run's latest part ran with
    agent_name = args.get("agent") or "oracle"
    options = dict(args.get("agent_options") or {})
    per_config = {c["name"]: dict(c.get("options") or {}) for c in args.get("configs") or []}  # a --configs run
    replay_options: dict[str, Any] = {}
    if agent_name == "llm":
        cache = cache_dir or (config.get("manifest") or {}).get("cache_dir")
        if not cache:
            raise ConfigError(f"{run_dir} was run without an LLM cache (CAPMJ_LLM_CACHE); nothing to replay from. "
                              "Give --cache DIR if the completions are cached elsewhere")
        if not Path(cache).is_dir():
            raise ConfigError(f"LLM cache folder {str(cache)!r} does not exist")
        replay_options = {"cache_dir": str(cache), "cache_only": True}
    agents: dict[str | None, Any] = {}

    def agent_of(config: str | None) -> Any:
        """The agent of a record's configuration (built once; the run's own options without one)."""
        if config not in agents:
            agents[config] = make_agent(agent_name, **{**per_config.get(config or "", options), **replay_options})
        return agents[config]

    agent_of(None if not per_config else next(iter(per_config)))  # bad options fail before any episode
    records, _ = read_records(run_dir / EPISODES)
    records.sort(key=lambda r: (r.config or "", r.task, r.seed))
    mismatches: list[dict[str, Any]] = []
    live = 0
    for rec in records:
        try:
            result = run_episode(get_task(rec.task), rec.seed, agent_of(rec.config))
        except CapmjError as exc:
            mismatches.append({"config": rec.config, "task": rec.task, "seed": rec.seed,
                               "reasons": [f"cannot replay: {exc}"]})
            continue
        new = as_record(EpisodeResult.from_dict(sanitize(result.to_dict())))  # as the grid would write it
        if new.llm is not None:
            live += new.llm.calls - new.llm.cached_calls - new.llm.failed_calls
        reasons = compare(rec, new, tol)
        if reasons:
            mismatches.append({"config": rec.config, "task": rec.task, "seed": rec.seed, "reasons": reasons})
        if progress is not None:
            progress(rec, reasons)
    return {"run": str(run_dir), "episodes": len(records), "passed": len(records) - len(mismatches),
            "http_calls": live, "tolerance": tol, "mismatches": mismatches}


def main(argv: Sequence[str]) -> int:
    p = argparse.ArgumentParser(prog="python -m capmj.bench replay-check",
                                description="Re-run a finished run from the LLM cache alone (zero HTTP calls) and "
                                            "check every episode reaches the same final poses and verdict.")
    p.add_argument("dir", type=Path, metavar="DIR")
    p.add_argument("--cache", type=Path, default=None, metavar="DIR",
                   help="LLM cache folder (default: the one recorded in DIR/config.json)")
    p.add_argument("--tol", type=float, default=TOL, help=f"pose tolerance (default {TOL:g})")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    args = p.parse_args(list(argv))

    def show(rec: EpisodeRecord, reasons: list[str]) -> None:
        where = f"[{rec.config}] " if rec.config is not None else ""
        print(f"{where}{rec.task} seed {rec.seed}: " + ("ok" if not reasons else "DIFFERS: " + "; ".join(reasons)),
              file=sys.stderr)

    try:
        out = replay_check(args.dir, cache_dir=args.cache, tol=args.tol, progress=show)
    except ConfigError as exc:
        print(f"capmj-bench replay-check: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(out, indent=2, sort_keys=True))
    else:
        print(f"replay-check {out['run']}: {out['passed']}/{out['episodes']} episode(s) identical "
              f"(tolerance {out['tolerance']:g}), {out['http_calls']} HTTP call(s)")
    return 0 if not out["mismatches"] else 1
