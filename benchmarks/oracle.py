"""Oracle success per task over the test split (odd seeds from 10001), through real physics.

The oracle solves each task from its Ravens-style oracle goals through the real pick-and-place
primitive, so a failure here is a bug in a task's goals or scene, or in the simulator.  Output as
``agent_grid.py`` describes: per-task JSON lines on stderr, a summary JSON object on stdout.

    python benchmarks/oracle.py [--tasks all] [--seeds 50] [--workers 2]
"""

from __future__ import annotations

from agent_grid import main

if __name__ == "__main__":
    raise SystemExit(main("oracle", __doc__))
