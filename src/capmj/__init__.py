"""capmj: LLM code-as-policies over long-horizon tabletop tasks, simulated in MuJoCo.

Layers depend downward only: ``sim`` (MuJoCo world, suction, motion, cameras) <- ``tasks``
(protocol, registry, goals, evaluation) <- ``agents`` (oracle, reference plans, LLM chain) <-
``bench`` / ``replay``.  Importing the top-level package imports nothing heavy.
"""

__version__ = "0.1.0"
