"""Offline reading of episode logs: ``python -m capmj.replay FILE.rrd`` (see :mod:`capmj.replay.cli`).

Everything here works from the ``.rrd`` file alone (``rerun.chunk.RrdReader``), no viewer needed.
"""

from capmj.replay.cli import EpisodeLog, LoggedImage, ReplayError, export_frames, iter_images, main, read_episode

__all__ = ["EpisodeLog", "LoggedImage", "ReplayError", "export_frames", "iter_images", "main", "read_episode"]
