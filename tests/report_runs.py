"""Small real runs for the tests of the report page and the evidence bundle (and the page's
screenshot in docs/): the oracle, and the LLM agent scripted through the tests' stub server.

The scripted LLM run is a fixture, never a result: on task A the first planner request gets (unless
told otherwise) a plan that stacks one block and then names an object that does not exist (a failed episode,
label ``unknown_object``), every later one the stub solver's plan (solved); a planner request of
any other task is answered HTTP 400, which the client does not retry (a provider failure: an
anomaly, label ``llm_error``).
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any, Sequence

from llm_stub_server import Reply, StubLLMServer, prompt_text
from stub_solver import _GOAL, PLAN, TASK

from capmj.bench.cli import main

__all__ = ["BROKEN_PLAN", "TASK", "llm_run", "oracle_run"]

BROKEN_PLAN = """```python
zone = [n for n in get_obj_names() if ' zone ' in n and get_color(n) == {color!r}][0]
blocks = [n for n in get_obj_names() if ' block ' in n]
put_first_on_second(blocks[0], zone)
put_first_on_second(blocks[1], 'fixed purple bowl with obj_id 99')
```"""


def oracle_run(out: Path, tasks: Sequence[str], seeds: str) -> Path:
    """The oracle on ``tasks`` × ``seeds`` in this process, logged (``.rrd``)."""
    assert main(["--tasks", ",".join(tasks), "--seeds", seeds, "--workers", "0", "--out", str(out),
                 "--no-progress"]) == 0
    return out


def _responder(broken_first: bool) -> Any:
    lock = threading.Lock()
    planned = [0]

    def respond(request: dict[str, Any]) -> Reply:
        found = _GOAL.findall(prompt_text(request).rstrip().splitlines()[-1])  # the query: the prompt's last line
        if not found:
            return Reply.error(400, "stub: this server only plans task A")
        with lock:
            planned[0] += 1
            first = broken_first and planned[0] == 1
        return Reply(text=(BROKEN_PLAN if first else PLAN).format(color=found[-1]))

    return respond


def llm_run(out: Path, tasks: Sequence[str], seeds: str, *extra: str, broken_first: bool = True) -> Path:
    """The LLM agent on ``tasks`` × ``seeds`` against the scripted stub server (see the module
    docstring; ``broken_first=False``: no broken plan), one episode at a time in this process, logged."""
    with StubLLMServer() as server:
        server.respond_with(_responder(broken_first))
        assert main(["--agent", "llm", "--model", "openai/stub", "--api-base", server.base_url, "--reporter", "none",
                     "--tasks", ",".join(tasks), "--seeds", seeds, "--workers", "0", "--concurrency", "1",
                     "--out", str(out), "--no-progress", *extra]) == 0
    return out
