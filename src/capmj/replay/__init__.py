"""Offline reading of episode logs: ``python -m capmj.replay FILE.rrd | RUN_DIR`` (see :mod:`capmj.replay.cli`).

Everything here works from the files alone (``rerun.chunk.RrdReader``), no viewer needed:
:mod:`~capmj.replay.reader` reads an episode log, :mod:`~capmj.replay.frames` exports its camera
images, :mod:`~capmj.replay.run_dir` lists a run's failed episodes, :mod:`~capmj.replay.viewer`
starts the viewer.
"""

from capmj.replay.cli import main
from capmj.replay.frames import depth_preview, export_frames
from capmj.replay.reader import EpisodeLog, LoggedImage, ReplayError, iter_images, read_episode
from capmj.replay.run_dir import FailedEpisode, failed_episodes

__all__ = ["EpisodeLog", "FailedEpisode", "LoggedImage", "ReplayError", "depth_preview", "export_frames",
           "failed_episodes", "iter_images", "main", "read_episode"]
