"""Episode logs: :class:`RerunRecorder` writes one ``.rrd`` per episode.  Running an episode with
it is :func:`capmj.runner.record_episode`: this package records, it does not run episodes.

Modules, one concept each: :mod:`~capmj.log.paths` (entity paths: the file format),
:mod:`~capmj.log.recorder` (the recorder), :mod:`~capmj.log.poses` (body poses between flushes,
and which are re-sent), :mod:`~capmj.log.clock` (the monotonic ``sim_time``),
:mod:`~capmj.log.images` (camera images), :mod:`~capmj.log.geometry` (table, object shapes,
robot), :mod:`~capmj.log.robot_mesh` (UR5e visual meshes with trimesh),
:mod:`~capmj.log.verdict3d` (failing objects, diagnostics and targets in 3D),
:mod:`~capmj.log.perception3d` (what an rgbd episode perceived, beside the true objects),
:mod:`~capmj.log.attempts` (one Markdown document per LLM attempt), :mod:`~capmj.log.summary`
(the episode summary), :mod:`~capmj.log.blueprint` (the viewer layout).

Importing this package is cheap: rerun is imported only when a recorder is created.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from capmj.log.paths import SUMMARY_JSON_PATH, SUMMARY_PATH, SUMMARY_SCHEMA, text_entity

if TYPE_CHECKING:
    from capmj.log.recorder import RerunRecorder

__all__ = ["RerunRecorder", "SUMMARY_PATH", "SUMMARY_JSON_PATH", "SUMMARY_SCHEMA", "text_entity"]


def __getattr__(name: str) -> Any:  # lazy: keep `import capmj.log` free of rerun
    if name == "RerunRecorder":
        from capmj.log.recorder import RerunRecorder

        return RerunRecorder
    if name == "record_episode":  # moved to capmj.runner; the old import path still works
        from capmj.runner import record_episode

        return record_episode
    raise AttributeError(f"module 'capmj.log' has no attribute {name!r}")
