"""Result files of a benchmark run: ``episodes.jsonl`` (append-only, crash-safe) and the summary statistics.

``episodes.jsonl`` has one JSON object per finished episode, an :class:`~capmj.records.EpisodeRecord`:
every field of the runner's :class:`~capmj.records.EpisodeResult` (task, seed, agent, model,
success, progress, reward, primitives, attempts, sim_s, wall_s, error, goal, diagnostics, llm, rrd,
final_poses, drift), plus ``failure`` (:mod:`capmj.bench.failures`), ``transcript`` (the episode's
LLM calls moved to ``transcripts/``, :mod:`capmj.bench.transcripts`) and ``schema``.
:func:`read_records` returns records (lines of older versions migrated, :mod:`capmj.bench.migrate`);
:func:`read_results` the same as plain dicts, for scripts.  Lines are appended by
one process only (the grid's parent) as one ``write`` of a complete line followed by ``fsync``, so
a run killed at any moment leaves complete lines plus at most one truncated last line, which
:func:`read_results` skips and :class:`ResultsWriter` cuts off before appending again.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

from capmj.atomic import write_json_atomic
from capmj.bench.anomalies import DEFAULT_THRESHOLD, denominator, section, split
from capmj.bench.failures import breakdown
from capmj.bench.migrate import as_record, load_record
from capmj.bench.profile import profile
from capmj.bench.rundir import CONFIG, EPISODES, SUMMARY_JSON, SUMMARY_MD, SUMMARY_PNG
from capmj.bench.spend import usage
from capmj.bench.stats import wilson
from capmj.errors import RecordError
from capmj.records import Episode, EpisodeRecord, Key
from capmj.records.notes import TURNS_USED_UP

SUMMARY_SCHEMA = "capmj.bench-summary/2"
"""``/2``: rates over the agent's episodes, anomalies apart (``anomalies``), ``profile``, ``stamp``."""
REQUIRED_KEYS: tuple[str, ...] = ("task", "seed", "agent", "model", "success", "progress", "primitives",
                                  "wall_s", "error", "rrd")



def episode_key(rec: Episode) -> Key:
    """The identity of an episode in a grid: (task, seed, agent, model)."""
    return rec.key


def read_records(path: str | Path) -> tuple[list[EpisodeRecord], int]:
    """The complete records of a jsonl file and the number of lines skipped (truncated, corrupt,
    or not a record).

    A missing file is empty.  When the same key appears twice (should not happen) the last wins.
    """
    path = Path(path)
    if not path.exists():
        return [], 0
    records: dict[tuple[str | None, str, int, str, str | None], EpisodeRecord] = {}
    bad = 0
    with open(path, "rb") as f:
        data = f.read()
    for raw in data.split(b"\n"):
        if not raw.strip():
            continue
        try:
            rec = load_record(json.loads(raw))
        except (ValueError, RecordError):
            bad += 1
            continue
        records[rec.grid_key] = rec
    return list(records.values()), bad


def read_results(path: str | Path) -> tuple[list[dict[str, Any]], int]:
    """:func:`read_records` as today's JSON dicts (for scripts that index lines by key)."""
    records, bad = read_records(path)
    return [r.to_dict() for r in records], bad


class ResultsWriter:
    """Appends result lines atomically (one ``os.write`` of a full line, then ``fsync``)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._repair()
        self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)

    def _repair(self) -> None:
        """Cut a truncated last line (a run killed mid-write) so the next line starts cleanly."""
        if not self.path.exists():
            return
        with open(self.path, "rb+") as f:
            data = f.read()
            if not data or data.endswith(b"\n"):
                return
            cut = data.rfind(b"\n") + 1  # 0 when the file holds only a partial line
            f.truncate(cut)
            f.flush()
            os.fsync(f.fileno())

    def write(self, record: EpisodeRecord | Mapping[str, Any]) -> None:
        if isinstance(record, EpisodeRecord):
            record = record.to_dict()
        line = (json.dumps(record, sort_keys=True, allow_nan=False, default=_json_default) + "\n").encode()
        view = memoryview(line)
        while view:  # os.write on a regular file writes everything in practice; loop for safety
            n = os.write(self._fd, view)
            view = view[n:]
        os.fsync(self._fd)

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1

    def __enter__(self) -> "ResultsWriter":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _json_default(v: Any) -> Any:
    if hasattr(v, "tolist"):
        return v.tolist()
    if isinstance(v, (set, frozenset, tuple)):
        return list(v)
    return str(v)


def sanitize(record: Mapping[str, Any]) -> dict[str, Any]:
    """A JSON-safe copy (NaN/inf become None) of a result record."""
    def fix(v: Any) -> Any:
        if isinstance(v, float) and not math.isfinite(v):
            return None
        if isinstance(v, Mapping):
            return {str(k): fix(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [fix(x) for x in v]
        return v
    return fix(dict(record))


# ---------------------------------------------------------------------- statistics
def stats(records: Sequence[EpisodeRecord]) -> dict[str, Any]:
    """n, successes, success rate with its 95 % Wilson interval, means and wall-time totals; for
    LLM episodes also ``loop`` (:func:`loop_stats`: verdicts, reporter accuracy, re-plans, tokens).

    Everything but ``llm_usage`` (what was really spent) is over the agent's episodes: ``n`` leaves
    out the anomalies (:mod:`capmj.bench.anomalies`), counted in ``anomalies`` (by label in
    ``anomaly_labels``); ``episodes`` = n + anomalies; ``denominator`` is the text printed beside
    the rate (``"12/18 episodes, 2 anomalies excluded"``)."""
    everything = list(records)
    records, anomalous = split(everything)
    n = len(records)
    k = sum(1 for r in records if r.success)
    lo, hi = wilson(k, n)

    def mean(values: Iterable[float | None]) -> float | None:
        vals = [float(v) for v in values if v is not None]
        return sum(vals) / len(vals) if vals else None

    wall = [float(r.wall_s) for r in records if r.wall_s is not None]
    out = {
        "failures": breakdown(records),
        "llm_usage": usage(everything),
        "n": n,
        "episodes": len(everything),
        "anomalies": len(anomalous),
        "anomaly_labels": breakdown(anomalous),
        "denominator": f"{k}/" + denominator(n, len(anomalous)),
        "successes": k,
        "success_rate": k / n if n else None,
        "ci95": [lo, hi],
        "mean_progress": mean(r.progress for r in records),
        "mean_primitives": mean(r.primitives for r in records),
        "mean_sim_s": mean(r.sim_s for r in records),
        "errors": sum(1 for r in records if r.error),
        "wall_s_total": sum(wall),
        "wall_s_mean": sum(wall) / len(wall) if wall else None,
    }
    loop = loop_stats(records)
    if loop is not None:
        out["loop"] = loop
    seen = perception_stats(records)
    if seen is not None:
        out["perception"] = seen
    return out


def perception_stats(records: Sequence[Episode]) -> dict[str, Any] | None:
    """The perception error of rgbd episodes (``record.perception``); None without any.

    ``reset`` pools each episode's first view (the scene as it starts), ``after_moves`` every view
    taken after a pick-and-place: objects, missed and false objects, kind / colour / size errors,
    the median of the views' median position errors and the largest error (mm), the largest
    fixture slot error (mm; None without a fixture).  ``erred`` counts
    the episodes whose last attempt acted on a wrong view or picked off target
    (:meth:`~capmj.records.PerceptionNotes.erred`), ``pick_misses`` those picks.
    """
    eps = [r for r in records if r.perception is not None]
    if not eps:
        return None

    def pooled(calls: Sequence[Any]) -> dict[str, Any]:
        medians = sorted(c.median_pos_mm for c in calls if c.median_pos_mm is not None)
        maxima = [c.max_pos_mm for c in calls if c.max_pos_mm is not None]
        slots = [c.max_slot_mm for c in calls if c.max_slot_mm is not None]
        return {"views": len(calls), "objects": sum(c.objects for c in calls),
                "missed": sum(c.missed for c in calls), "false": sum(c.false_detections for c in calls),
                "kind_errors": sum(c.kind_errors for c in calls), "color_errors": sum(c.color_errors for c in calls),
                "size_errors": sum(c.size_errors for c in calls),
                "median_pos_mm": _median(medians), "max_pos_mm": max(maxima) if maxima else None,
                "max_slot_mm": max(slots) if slots else None}

    notes = [r.perception for r in eps if r.perception is not None]
    return {
        "episodes": len(eps),
        "perceivers": sorted({n.perceiver for n in notes}),
        "erred": sum(r.perception.erred(max(r.attempts, 1)) for r in eps if r.perception is not None),
        "pick_misses": sum(len(n.pick_misses) for n in notes),
        "reset": pooled([n.calls[0] for n in notes if n.calls]),
        "after_moves": pooled([c for n in notes for c in n.calls if c.stage != "reset"]),
    }


def _median(sorted_values: Sequence[float]) -> float | None:
    n = len(sorted_values)
    if not n:
        return None
    mid = n // 2
    return sorted_values[mid] if n % 2 else (sorted_values[mid - 1] + sorted_values[mid]) / 2


def _share(k: int, n: int) -> float | None:
    return k / n if n else None


def loop_stats(records: Sequence[Episode]) -> dict[str, Any] | None:
    """The closed loop of LLM episodes (``record.llm.attempts``); None without any.

    Reporter accuracy compares each attempt's reporter verdict with the task predicate evaluated
    on the same state (both recorded per attempt by the LLM agent): ``agree`` when equal,
    ``false_positives`` = verdict True but predicate False, ``false_negatives`` = verdict False
    but predicate True; ``agreement`` = agree / compared.  ``verdict_rate`` = attempts whose
    reporter reached True/False / attempts in which a reporter ran (a plan that raised is not
    judged).  ``identical_replans`` counts attempts 2, 3, ... whose plan equals an earlier
    attempt's plan (after the retries), ``not_rerun`` those of them that were therefore not run,
    ``extra_requests`` the planner requests made because an answer repeated an earlier plan (records
    written before retries existed count their ``extra_request`` flag as one).  Tokens are prompt +
    completion per episode.
    """
    eps = [r for r in records if r.llm is not None]
    if not eps:
        return None
    attempts = [a for r in eps for a in r.llm_attempts]
    judged = [a for a in attempts if a.verdict_source is not None]
    reached = [a for a in judged if a.verdict is not None]
    compared = [a for a in reached if a.predicate is not None]
    agree = sum(a.verdict is a.predicate for a in compared)
    fp = sum(a.verdict is True and a.predicate is False for a in compared)
    fn = sum(a.verdict is False and a.predicate is True for a in compared)
    sources = {src: sum(a.verdict_source == src for a in judged) for src in ("code", "repair", "direct", "unknown")}
    replans = [a for a in attempts if a.code_differs is not None]
    identical = sum(a.code_differs is False for a in replans)
    prompt = [r.llm.prompt_tokens for r in eps if r.llm is not None]
    completion = [r.llm.completion_tokens for r in eps if r.llm is not None]
    n = len(eps)
    return {
        "episodes": n,
        "attempts": len(attempts),
        "mean_attempts": len(attempts) / n,
        "reporter_runs": len(judged),
        "verdicts": len(reached),
        "verdict_rate": _share(len(reached), len(judged)),
        "verdict_sources": sources,
        "unknown_stops": sum(a.on_unknown == "stop" for a in attempts),
        "compared": len(compared),
        "agree": agree,
        "false_positives": fp,
        "false_negatives": fn,
        "agreement": _share(agree, len(compared)),
        "replans": len(replans),
        "identical_replans": identical,
        "identical_replan_rate": _share(identical, len(replans)),
        "not_rerun": sum(bool(a.not_run) for a in replans),
        "extra_requests": sum(a.extra_requests for a in attempts),
        "tokens_total": sum(prompt) + sum(completion),
        "mean_tokens": (sum(prompt) + sum(completion)) / n,
        "mean_prompt_tokens": sum(prompt) / n,
        "mean_completion_tokens": sum(completion) / n,
        **_turn_stats(eps),
        **_tool_stats(eps),
    }


def _turn_stats(eps: Sequence[Episode]) -> dict[str, Any]:
    """``{"turns": ...}`` of the multi-turn episodes among ``eps`` (see :func:`loop_stats`); {} without any."""
    multi = [r.llm for r in eps if r.llm is not None and r.llm.interaction == "multi"]
    if not multi:
        return {}
    finished = [m for m in multi if m.finish_agreed is not None]
    agree = sum(m.finish_agreed is True for m in finished)
    return {"turns": {
        "episodes": len(multi), "mean_turns": sum(len(m.attempts) for m in multi) / len(multi),
        "finished": len(finished), "finish_agree": agree, "finish_false_positives": len(finished) - agree,
        "finish_agreement": _share(agree, len(finished)),
        "no_finish": sum(m.stopped == TURNS_USED_UP for m in multi)}}


def _tool_stats(eps: Sequence[Episode]) -> dict[str, Any]:
    """``{"tools": ...}`` of the ``--policy tools`` episodes among ``eps``: turns, function calls and how
    many the model wrote as JSON in its text (``content_json``), episodes the model ended (no call or
    FINISH) and whether the predicate then held, episodes out of turns; {} without any."""
    tools = [r.llm for r in eps if r.llm is not None and r.llm.policy == "tools"]
    if not tools:
        return {}
    calls = [c for m in tools for t in m.attempts for c in t.tool_calls or ()]
    in_text = sum(c.form == "content_json" for c in calls)
    return {"tools": {
        "episodes": len(tools), "mean_turns": sum(len(m.attempts) for m in tools) / len(tools),
        "calls": len(calls), "content_json_calls": in_text, "content_json_share": _share(in_text, len(calls)),
        "ended_by_model": sum(m.finish_agreed is not None for m in tools),
        "finish_agree": sum(m.finish_agreed is True for m in tools),
        "no_finish": sum(m.stopped == TURNS_USED_UP for m in tools)}}


def config_of(rec: Episode) -> tuple[str, str | None]:
    return (rec.agent, rec.model)


def default_label(agent: str, model: str | None) -> str:
    return agent if not model else f"{agent} {model}"


def record_label(rec: EpisodeRecord) -> str:
    """A record's configuration label: its ``--configs`` name, else ``agent model``."""
    return rec.config if rec.config is not None else default_label(*config_of(rec))


def summarize(records: Iterable[EpisodeRecord | Mapping[str, Any]],
              label_of: Callable[[EpisodeRecord], str] | None = None,
              anomaly_threshold: float = DEFAULT_THRESHOLD) -> dict[str, Any]:
    """Per-task and overall statistics for each configuration found in ``records``.

    A configuration is a record's ``--configs`` name, else (agent, model), unless ``label_of`` maps
    records to other labels (e.g. one per result folder).  ``summary["anomalies"]`` counts and
    lists the episodes that failed through no fault of the agent
    (:func:`capmj.bench.anomalies.section`; ``exceeded`` when their share is above ``anomaly_threshold``).  ``summary["tasks"][task][label]`` and ``summary["overall"][label]`` hold
    :func:`stats`; ``summary["configs"][label]`` says which agent/model a label stands for and what
    its planner API read (``perception``: the perceiver of rgbd episodes; absent for the simulator).
    Parsed lines (dicts) are loaded as records first (:func:`capmj.bench.migrate.as_record`).
    """
    recs = [as_record(r) for r in records]
    configs: dict[str, dict[str, Any]] = {}
    by: dict[str, dict[str, list[EpisodeRecord]]] = {}
    overall: dict[str, list[EpisodeRecord]] = {}
    tasks: list[str] = []
    for r in recs:
        cfg = config_of(r)
        label = label_of(r) if label_of else record_label(r)
        configs.setdefault(label, {"agent": cfg[0], "model": cfg[1], "perception": set()})["perception"].add(
            r.perception.perceiver if r.perception is not None else "state")
        t = r.task
        if t not in tasks:
            tasks.append(t)
        by.setdefault(t, {}).setdefault(label, []).append(r)
        overall.setdefault(label, []).append(r)
    for c in configs.values():  # state-only configurations keep the shape summaries always had
        seen = c.pop("perception") - {"state"}
        if seen:
            c["perception"] = ", ".join(sorted(seen))
    prof = profile(recs, label_of or record_label, order=list(overall))
    return {
        "schema": SUMMARY_SCHEMA,
        "configs": configs,
        "tasks": {t: {lab: stats(rs) for lab, rs in by[t].items()} for t in sorted(tasks)},
        "overall": {lab: stats(rs) for lab, rs in overall.items()},
        "anomalies": section(recs, anomaly_threshold, label_of or record_label),
        "profile": prof,
        "comparisons": prof["paired"],
    }


def load_json(path: str | Path) -> dict[str, Any] | None:
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def write_result_json(path: str | Path, data: Any) -> None:
    """A result folder's JSON file (``config.json``, ``summary.json``): indent 2, sorted keys,
    numpy values as lists; written atomically (:func:`capmj.atomic.write_json_atomic`)."""
    write_json_atomic(path, data, indent=2, sort_keys=True, default=_json_default)


__all__ = [
    "CONFIG", "EPISODES", "REQUIRED_KEYS", "ResultsWriter", "SUMMARY_JSON", "SUMMARY_MD", "SUMMARY_PNG",
    "config_of", "default_label", "record_label", "episode_key", "load_json", "loop_stats", "perception_stats", "read_records", "read_results", "sanitize",
    "stats",
    "summarize",
    "wilson", "write_result_json",
]
