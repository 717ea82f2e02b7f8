"""``python -m capmj.bench export RUN --bundle OUT.zip``: a run's evidence in one zip file.

The shape leaderboards ask for — which model and harness revision, what it cost, how many episodes
were stopped or inconclusive, and the command that reproduces it — next to everything needed to
check it: the run's ``episodes.jsonl``, ``config.json``, LLM transcripts and failed-episode
thumbnails exactly as the run folder holds them, ``summary.json``/``summary.md`` rebuilt from those
episodes by the report code (:func:`capmj.bench.report.report`; the run's own timing facts kept),
``manifest.json`` (the run manifest of ``config.json``), the report page (``report.html``,
:mod:`capmj.bench.page`), ``versions.json`` (the versions the run recorded, and those of the
environment that made the bundle), ``reproduce.sh`` and ``evidence.json`` (the figures per
configuration and the SHA-256 of every other file).  Unzipped, the folder is a result folder:
``report`` rebuilds the same summary from it.  ``.rrd`` logs are left out unless asked for
(they are large); keys never are in a run folder (:mod:`capmj.llm.keys`).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import shlex
import tempfile
import zipfile
from pathlib import Path
from typing import Any, Mapping

from capmj.bench.manifest import git_state, package_versions
from capmj.bench.page import REPORT_HTML, write_page
from capmj.bench.config import reproduce_commands
from capmj.bench.page.view import profile_view
from capmj.bench.report import report
from capmj.bench.results import load_json
from capmj.bench.rundir import (
    CONFIG,
    EPISODES,
    RRD_DIR,
    SUMMARY_JSON,
    SUMMARY_MD,
    THUMBS_DIR,
    TRANSCRIPTS_DIR,
)
from capmj.errors import ConfigError

__all__ = ["EVIDENCE", "EVIDENCE_SCHEMA", "MANIFEST", "REPRODUCE", "VERSIONS", "evidence", "write_bundle"]

EVIDENCE_SCHEMA = "capmj.evidence/1"
EVIDENCE = "evidence.json"
MANIFEST = "manifest.json"
VERSIONS = "versions.json"
REPRODUCE = "reproduce.sh"
STOPPED_LABELS = ("budget", "no_finish")
"""Failure labels of episodes stopped by a limit rather than ended by the agent: a budget (wall
time, lines, API calls, primitives, simulation steps, tokens) or the turns of a multi-turn episode."""


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _json(data: Any) -> bytes:
    return (json.dumps(data, indent=2, sort_keys=True, default=str) + "\n").encode()


def reproduce_script(cfg: Mapping[str, Any]) -> str:
    """``reproduce.sh``: check out the recorded revision, install, run the recorded commands."""
    git = (cfg.get("manifest") or {}).get("git") or {}
    version = (cfg.get("versions") or {}).get("capmj", "unknown")
    lines = ["#!/usr/bin/env bash", "# The commands that made this run (config.json), from a capmj checkout.",
             f"# capmj {version}, git revision {git.get('revision') or 'unknown'}"
             + (" (the run had uncommitted changes: the revision alone may not reproduce it)" if git.get("dirty") else ""),
             "# A cloud model needs its key in the environment (e.g. OPENAI_API_KEY); none is stored here.",
             "set -euo pipefail"]
    if git.get("revision"):
        lines.append(f"git checkout {shlex.quote(git['revision'])}")
    lines += ['pip install -e ".[dev]"', "export MUJOCO_GL=egl"]
    commands = reproduce_commands(cfg)
    lines += commands if commands else ["# (config.json records no command line)"]
    return "\n".join(lines) + "\n"


def evidence(summary: Mapping[str, Any], cfg: Mapping[str, Any]) -> dict[str, Any]:
    """``evidence.json`` without its file list: per configuration the episodes run, the agent's
    episodes (anomalies excluded when the summary counts them), successes, rate and Wilson interval,
    anomalies (inconclusive: harness failures, when the summary counts them),
    episodes stopped by a limit, LLM tokens, calls and cost; the model, the harness revision,
    the task stamp and the reproduction commands."""
    view = profile_view(summary)
    manifest = cfg.get("manifest") or {}
    git = manifest.get("git") or {}
    versions = manifest.get("packages") or cfg.get("versions") or {}
    configs: dict[str, Any] = {}
    for label in view.configs:
        cell = view.overall[label]
        eff = view.efficiency.get(label) or {}
        legacy = summary["overall"].get(label) or {}
        failures = legacy.get("failures") or {}
        usage = legacy.get("llm_usage") or {}
        configs[label] = {
            **(summary.get("configs") or {}).get(label, {}),
            "episodes_run": cell["n"] + (cell.get("anomalies") or 0),
            "episodes": cell["n"], "successes": cell["successes"], "success_rate": cell["success_rate"],
            "ci95": cell["ci95"], "inconclusive": cell.get("anomalies"),
            "stopped_by_limit": sum(failures.get(lab, 0) for lab in STOPPED_LABELS),
            "failures": failures, "anomaly_labels": legacy.get("anomaly_labels"),
            "llm_calls": usage.get("calls"), "tokens": usage.get("tokens"),
            "cost_usd": usage.get("cost_usd") if usage.get("cost_known", True) else None,
            "per_episode": eff.get("per_episode"), "per_solved_episode": eff.get("per_solved"),
        }
    anomalies = summary.get("anomalies")
    return {
        "schema": EVIDENCE_SCHEMA,
        "agent": cfg.get("agent"), "model": cfg.get("model") or manifest.get("model"),
        "harness": {"capmj": versions.get("capmj"), "git_revision": git.get("revision"), "git_dirty": git.get("dirty"),
                    "python": versions.get("python"), "mujoco": versions.get("mujoco"),
                    "litellm": versions.get("litellm")},
        "task_stamp": summary.get("stamp") or cfg.get("stamp"),
        "tasks": cfg.get("tasks"), "seeds": cfg.get("seeds"), "started_at": cfg.get("started_at"),
        "configurations": configs,
        "inconclusive": None if anomalies is None else anomalies.get("count"),
        "inconclusive_note": "anomalies: harness failures (provider, infrastructure), excluded from the rates"
                             if anomalies is not None else "this run's summary does not count anomalies apart",
        "reproduce": reproduce_commands(cfg),
    }


def _run_files(run: Path, with_rrd: bool) -> list[Path]:
    """The run folder's files that go into the bundle unchanged (relative paths, sorted)."""
    out = [Path(EPISODES), Path(CONFIG)]
    for folder in (TRANSCRIPTS_DIR, THUMBS_DIR) + ((RRD_DIR,) if with_rrd else ()):
        if (run / folder).is_dir():
            out += sorted(p.relative_to(run) for p in (run / folder).rglob("*") if p.is_file())
    return out


def write_bundle(run_dir: str | Path, out: str | Path, *, with_rrd: bool = False) -> Path:
    """Write the evidence bundle of the result folder ``run_dir`` to the zip file ``out``.

    Raises :class:`ConfigError` for a folder that is not a result folder (no ``episodes.jsonl`` or
    no ``config.json``); the run folder itself is not changed."""
    run = Path(run_dir)
    if not (run / EPISODES).is_file() or not (run / CONFIG).is_file():
        raise ConfigError(f"{run} is not a result folder (it needs {EPISODES} and {CONFIG})")
    cfg = load_json(run / CONFIG) or {}
    summary, md = report([run])
    previous = load_json(run / SUMMARY_JSON) or {}
    if "run" in previous:  # the timing facts of the run that produced the folder
        summary["run"] = previous["run"]
    made: dict[str, bytes] = {SUMMARY_JSON: _json(summary), SUMMARY_MD: md.encode(),
                              MANIFEST: _json(cfg.get("manifest") or {}), REPRODUCE: reproduce_script(cfg).encode()}
    made[VERSIONS] = _json({"run": {**(cfg.get("versions") or {}), "git": (cfg.get("manifest") or {}).get("git"),
                                    "task_stamp": summary.get("stamp") or cfg.get("stamp")},
                            "bundle": {**package_versions(), "git": git_state()}})
    with tempfile.TemporaryDirectory(prefix="capmj-bundle-") as tmp:
        made[REPORT_HTML] = write_page(Path(tmp) / REPORT_HTML, summary, [run],
                                       title=f"capmj benchmark report: {run.name}").read_bytes()
    files = _run_files(run, with_rrd)
    facts = evidence(summary, cfg)
    facts["bundled_at"] = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    facts["files"] = {**{p.as_posix(): _sha((run / p).read_bytes()) for p in files},
                      **{name: _sha(data) for name, data in made.items()}}
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp_zip = out.with_name(f".{out.name}.tmp")
    with zipfile.ZipFile(tmp_zip, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr(EVIDENCE, _json(facts))
        for name, data in sorted(made.items()):
            z.writestr(name, data)
        for p in files:
            z.write(run / p, p.as_posix())
    tmp_zip.replace(out)
    return out
