"""Reference-plan success per task over the test split (odd seeds from 10001), through real physics.

The reference plans (``prompts/reference/<task>.py``) run through the same planner API and sandbox
as LLM code, so a failure here is a bug in the API, a plan, a task or the simulator.  Output as
``agent_grid.py`` describes: per-task JSON lines on stderr, a summary JSON object on stdout.

    python benchmarks/reference.py [--tasks all] [--seeds 50] [--workers 2]
"""

from __future__ import annotations

from agent_grid import main

if __name__ == "__main__":
    raise SystemExit(main("reference", __doc__))
