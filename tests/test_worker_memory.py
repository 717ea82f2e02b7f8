"""The memory limit of a pool worker: the backstop behind the sandbox's size budgets.

A plan that allocates through a route the budgets cannot foresee (``str`` called through
``map``) must end as a ``BudgetExceeded`` of its episode when the worker's limit is reached, not
take the machine's memory.  Runs in a fresh interpreter so the limit binds only there.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

from capmj.bench.worker import MEMORY_ENV, limit_memory
from capmj.errors import ConfigError

PROBE = textwrap.dedent("""
    import json, resource
    from capmj.bench.worker import limit_memory
    from capmj.agents.sandbox import run_code
    from capmj.errors import BudgetExceeded
    mb = limit_memory()
    plan = "a = [0] * 4000000\\nt = list(map(str, [a] * 60))\\n"  # 60 texts of 12 MB: 720 MB, never sized
    try:
        run_code(plan, {}, program="the plan")
        out = {"error": None}
    except BudgetExceeded as e:
        out = {"error": type(e).__name__, "text": str(e)}
    out["limit_mb"] = mb
    out["rlimit"] = resource.getrlimit(resource.RLIMIT_DATA)[0] >> 20
    print(json.dumps(out))
""")


def test_an_allocation_past_the_workers_memory_limit_is_a_budget_failure_of_the_plan():
    env = {**os.environ, MEMORY_ENV: "400"}
    r = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=120, env=env)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert out["limit_mb"] == 400 and out["rlimit"] == 400
    assert out["error"] == "BudgetExceeded" and "ran out of memory" in out["text"], out


def test_a_bad_memory_setting_names_the_variable(monkeypatch):
    monkeypatch.setenv(MEMORY_ENV, "lots")
    with pytest.raises(ConfigError, match=MEMORY_ENV):
        limit_memory()
    monkeypatch.setenv(MEMORY_ENV, "0")
    assert limit_memory() is None
