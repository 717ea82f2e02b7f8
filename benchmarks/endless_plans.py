"""How fast the deterministic plan budget stops hostile code, as JSON.

Runs endless and allocation-hungry plans in the sandbox with the LLM agent's default plan budget
(``capmj.agents.llm_agent.planner.DEFAULT_PLAN_BUDGET``) and prints, per program, which budget stopped it,
after how many executed lines (the same on every machine) and the wall time it took (this
machine, under its current load).  The issue's target: ``while True: pass`` ends in < 2 s.

    python benchmarks/endless_plans.py
"""

from __future__ import annotations

import json
import os
import platform
import time

from capmj.agents.llm_agent.planner import DEFAULT_PLAN_BUDGET
from capmj.agents.sandbox import run_code
from capmj.errors import BudgetExceeded

PROGRAMS = {
    "while_true_pass": "while True: pass",
    "while_true_counter": "i = 0\nwhile True:\n    i += 1",
    "while_true_zeros": "while True:\n    x = np.zeros(10**6)",
    "nested_for": "for i in range(10**7):\n    for j in range(10**7):\n        pass",
    "swallowing_except": "while True:\n    try:\n        while True:\n            pass\n    except:\n        pass",
}


def main() -> int:
    rows = {}
    for name, code in PROGRAMS.items():
        start = time.perf_counter()
        try:
            run_code(code, {}, budget=DEFAULT_PLAN_BUDGET, program="the plan")
            message = "finished"
        except BudgetExceeded as exc:
            message = str(exc)
        rows[name] = {"seconds": round(time.perf_counter() - start, 3), "error": message}
    print(json.dumps({"budget": {"max_lines": DEFAULT_PLAN_BUDGET.max_lines,
                                 "max_total_elements": DEFAULT_PLAN_BUDGET.max_total_elements,
                                 "wall_s": DEFAULT_PLAN_BUDGET.wall_s},
                      "programs": rows, "python": platform.python_version(),
                      "load_avg_1min": round(os.getloadavg()[0], 2)}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
