"""Episode logs: :class:`RerunRecorder` writes one ``.rrd`` per episode; :func:`record_episode` runs
an episode with it.

Importing this package is cheap: rerun is imported only when a recorder is created.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from capmj.agents.base import Budget
    from capmj.log.rerun_log import RerunRecorder
    from capmj.runner import EpisodeResult

__all__ = ["RerunRecorder", "record_episode", "SUMMARY_PATH", "SUMMARY_JSON_PATH", "SUMMARY_SCHEMA"]


def __getattr__(name: str) -> Any:  # lazy: keep `import capmj.log` free of rerun
    if name in ("RerunRecorder", "SUMMARY_PATH", "SUMMARY_JSON_PATH", "SUMMARY_SCHEMA", "text_entity",
                "summary_markdown"):
        from capmj.log import rerun_log

        return getattr(rerun_log, name)
    raise AttributeError(f"module 'capmj.log' has no attribute {name!r}")


def record_episode(task: Any, seed: int, agent: Any, path: str | Path | None, *, images: bool = False,
                   budget: "Budget | None" = None) -> "EpisodeResult":
    """Run one episode; when ``path`` is given, log it to that ``.rrd`` (summary included) and return
    the result with ``rrd`` set to the path.  With ``path=None`` nothing is logged."""
    from dataclasses import replace

    from capmj.runner import run_episode

    if path is None:
        return run_episode(task, seed, agent, budget=budget)
    from capmj.log.rerun_log import RerunRecorder

    name = getattr(task, "name", str(task))
    rec = RerunRecorder(path, task=name, seed=seed, agent=getattr(agent, "name", None),
                        model=getattr(agent, "model", None), images=images)
    try:
        result = run_episode(task, seed, agent, budget=budget, recorder=rec)
        result = replace(result, rrd=str(path))
        rec.finish(result)
    finally:
        rec.close()
    return result
