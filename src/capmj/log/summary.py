"""The episode summary stored in every ``.rrd`` (``/summary`` Markdown, ``/summary_json`` JSON).

The Markdown reads top-down the way a failure is investigated: verdict, what failed (the
diagnostics), then the error that ended the agent, then the primitives and LLM usage.
"""

from __future__ import annotations

import json
import math
from typing import Any, Mapping

import numpy as np


def jsonable(v: Any) -> Any:
    """``v`` with numpy values, tuples and non-finite floats turned into plain JSON values."""
    if isinstance(v, Mapping):
        return {str(k): jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if v is None or isinstance(v, (str, int, float, bool)):
        return v
    return str(v)


def fmt_vec(v: Any) -> str:
    """``(0.500, 0.100, 0.020)`` for a numeric sequence, ``-`` for None."""
    if isinstance(v, (list, tuple)) and v and all(isinstance(x, (int, float)) for x in v):
        return "(" + ", ".join(f"{float(x):.3f}" for x in v) + ")"
    return "-" if v is None else str(v)


def summary_markdown(s: Mapping[str, Any]) -> str:
    """The Markdown rendering of a summary dict (what ``/summary`` holds)."""
    verdict = "SUCCESS" if s.get("success") else "FAILURE"
    lines = [f"# {verdict}: {s.get('task')} — seed {s.get('seed')}", "",
             f"progress {float(s.get('progress') or 0):.2f} · reward {float(s.get('reward') or 0):.2f} · "
             f"agent {s.get('agent')}" + (f" ({s.get('model')})" if s.get("model") else ""), "",
             f"**Goal:** {s.get('goal') or '-'}"]
    diags = s.get("diagnostics") or []
    if diags:
        lines += ["", "## Diagnostics", ""] + [f"- {d}" for d in diags]
    if s.get("error"):
        lines += ["", "## Error", "", "```text", str(s["error"]), "```"]
    lines += ["", f"primitives {s.get('primitives')} · attempts {s.get('attempts')} · "
                  f"simulated {float(s.get('sim_s') or 0):.2f} s · wall {float(s.get('wall_s') or 0):.2f} s"]
    prims = s.get("primitive_log") or []
    if prims:
        lines += ["", "## Primitives", "", "| # | attempt | status | object | pick | place | final |",
                  "|---|---|---|---|---|---|---|"]
        for p in prims:
            lines.append(f"| {p.get('index')} | {p.get('attempt')} | {p.get('status')} | {fmt_vec(p.get('obj_id'))} | "
                         f"{fmt_vec(p.get('pick'))} | {fmt_vec(p.get('place'))} | {fmt_vec(p.get('final_pos'))} |")
    llm = {k: v for k, v in (s.get("llm") or {}).items() if k != "attempts"}
    if llm:
        lines += ["", "## LLM usage", "", "```json", json.dumps(llm, indent=2, sort_keys=True), "```"]
    return "\n".join(lines) + "\n"


__all__ = ["fmt_vec", "jsonable", "summary_markdown"]
