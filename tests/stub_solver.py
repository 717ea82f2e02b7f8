"""A scripted planner for task A (stack-all-blocks-on-a-zone) behind the stub LLM server.

A fixture for throughput and determinism checks of the bench's executors, never a result: the
answer is computed from the goal in the prompt, so every episode succeeds through the real sandbox,
API and physics while the server decides how long the "model" takes (``latency_s``).
"""

from __future__ import annotations

import re
from typing import Any

from llm_stub_server import Reply, prompt_text

TASK = "stack-all-blocks-on-a-zone"
_GOAL = re.compile(r"Stack all blocks in the (\w+) zone")

PLAN = """```python
zone = [n for n in get_obj_names() if ' zone ' in n and get_color(n) == {color!r}][0]
for block in [n for n in get_obj_names() if ' block ' in n]:
    put_first_on_second(block, zone)
```"""


def solver(latency_s: float = 0.0):
    """A stub-server responder answering every planner request with a plan that solves task A."""

    def respond(request: dict[str, Any]) -> Reply:
        found = _GOAL.findall(prompt_text(request))
        if not found:
            return Reply.error(400, "stub solver: not a task-A planner request")
        return Reply(text=PLAN.format(color=found[-1]), delay_s=latency_s)

    return respond
