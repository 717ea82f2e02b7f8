"""Oracle demonstration datasets in the Ravens/CLIPort on-disk layout (see :mod:`capmj.demos.dataset`)
and a typed loader.  Collect them with ``python -m capmj.demos``; read with :func:`load`."""

from capmj.demos.dataset import DemoStep, episodes, load, split_seeds

__all__ = ["DemoStep", "episodes", "load", "split_seeds"]
