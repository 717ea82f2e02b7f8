"""Episode logs: :class:`RerunRecorder` writes one ``.rrd`` per episode; :func:`record_episode` runs
an episode with it.

Modules, one concept each: :mod:`~capmj.log.paths` (entity paths: the file format),
:mod:`~capmj.log.recorder` (the recorder), :mod:`~capmj.log.clock` (the monotonic ``sim_time``),
:mod:`~capmj.log.images` (camera images), :mod:`~capmj.log.geometry` (table, object shapes,
robot), :mod:`~capmj.log.robot_mesh` (UR5e visual meshes with trimesh),
:mod:`~capmj.log.verdict3d` (failing objects, diagnostics and targets in 3D),
:mod:`~capmj.log.attempts` (one Markdown document per LLM attempt), :mod:`~capmj.log.summary`
(the episode summary), :mod:`~capmj.log.blueprint` (the viewer layout).

Importing this package is cheap: rerun is imported only when a recorder is created.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from capmj.log.paths import SUMMARY_JSON_PATH, SUMMARY_PATH, SUMMARY_SCHEMA, text_entity

if TYPE_CHECKING:
    from capmj.agents.base import Budget
    from capmj.log.recorder import RerunRecorder
    from capmj.runner import EpisodeResult

__all__ = ["RerunRecorder", "record_episode", "SUMMARY_PATH", "SUMMARY_JSON_PATH", "SUMMARY_SCHEMA", "text_entity"]


def __getattr__(name: str) -> Any:  # lazy: keep `import capmj.log` free of rerun
    if name == "RerunRecorder":
        from capmj.log.recorder import RerunRecorder

        return RerunRecorder
    raise AttributeError(f"module 'capmj.log' has no attribute {name!r}")


def _oracle_goals(task: Any, seed: int) -> tuple:
    """The task's oracle goals for this seed (where objects should end), or () if they fail."""
    from capmj.tasks.protocol import make_scene

    try:
        return tuple(task.oracle_goals(make_scene(task, seed)))
    except Exception:  # noqa: BLE001 - the episode itself reports a broken task
        return ()


def record_episode(task: Any, seed: int, agent: Any, path: str | Path | None, *, images: bool = False,
                   budget: "Budget | None" = None) -> "EpisodeResult":
    """Run one episode; when ``path`` is given, log it to that ``.rrd`` (summary included) and return
    the result with ``rrd`` set to the path.  With ``path=None`` nothing is logged."""
    from dataclasses import replace

    from capmj.runner import run_episode

    if path is None:
        return run_episode(task, seed, agent, budget=budget)
    from capmj.log.recorder import RerunRecorder

    name = getattr(task, "name", str(task))
    rec = RerunRecorder(path, task=name, seed=seed, agent=getattr(agent, "name", None),
                        model=getattr(agent, "model", None), images=images, goals=_oracle_goals(task, seed))
    try:
        result = run_episode(task, seed, agent, budget=budget, recorder=rec)
        result = replace(result, rrd=str(path))
        rec.finish(result)
    finally:
        rec.close()
    return result
