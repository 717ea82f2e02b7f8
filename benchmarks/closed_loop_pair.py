"""Two closed-loop bench runs on the same episodes, digested: does the reporter help or hurt?

Issue #26 asks for closed-loop runs with ``--reporter text`` and with ``--reporter none`` on the
same tasks and seeds: success of each, how often the reporter's verdicts agreed with the task
predicate (FP: "achieved" on a failed state, FN: "not achieved" on an achieved one), and the
episodes one run solved and the other did not.  ``python -m capmj.bench report A B`` compares the
success figures; this script adds what only the attempt records say: every attempt's loop rule
(``rule``), its verdict next to the predicate on the same state, and the confidence the ``careful``
loop acted on.  It reads ``episodes.jsonl`` only, so it also digests a run that is still going.

    python benchmarks/closed_loop_pair.py runs/loop-none runs/loop-careful > pair.json

Prints one JSON object: ``runs.<name>`` (success, failure labels, rules, verdicts vs predicate,
wall time) and ``paired`` (episodes in both, solved by both / only A / only B, and the McNemar p of
``capmj.bench.stats``).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path
from typing import Any

from capmj.bench.results import read_results
from capmj.bench.stats import mcnemar_exact


def episodes(run_dir: Path) -> dict[tuple[str, int], dict[str, Any]]:
    """The run's episode records by (task, seed), read by the bench's own reader: a line a running
    bench is still writing is skipped, a later line for the same episode wins."""
    return {(str(r["task"]), int(r["seed"])): r for r in read_results(run_dir / "episodes.jsonl")[0]}


def verdict_counts(attempts: list[dict[str, Any]]) -> dict[str, int]:
    """Judged attempts: the reporter's verdict against the predicate on the same state."""
    c = Counter({"judged": 0, "agree": 0, "fp": 0, "fn": 0, "unknown": 0, "high_confidence": 0})
    for a in attempts:
        verdict, truth = a.get("verdict"), a.get("predicate")
        if a.get("verdict_source") is None and verdict is None:
            continue  # not judged (no reporter, or a plan that raised under the thesis loop)
        c["judged"] += 1
        c["high_confidence"] += a.get("confidence") == "high"
        if verdict is None:
            c["unknown"] += 1
        elif verdict == truth:
            c["agree"] += 1
        else:
            c["fp" if verdict else "fn"] += 1
    return dict(c)


def digest_run(eps: dict[tuple[str, int], dict[str, Any]]) -> dict[str, Any]:
    attempts = [a for e in eps.values() for a in (e.get("llm") or {}).get("attempts", [])]
    return {
        "success": sum(bool(e["success"]) for e in eps.values()), "episodes": len(eps),
        "failure_labels": dict(Counter(str(e.get("failure")) for e in eps.values() if not e["success"])),
        "infrastructure_failures": sum(e.get("failure") == "infrastructure" for e in eps.values()),
        "rules": dict(Counter(str(a.get("rule")) for a in attempts)),
        "verdicts_vs_predicate": verdict_counts(attempts),
        "wall_s_total": round(sum(float(e.get("wall_s") or 0) for e in eps.values()), 1),
        "tokens": sum(int((e.get("llm") or {}).get("prompt_tokens") or 0)
                      + int((e.get("llm") or {}).get("completion_tokens") or 0) for e in eps.values()),
        "episodes_detail": [{"task": t, "seed": s, "success": bool(e["success"]), "failure": e.get("failure"),
                             "attempts": [{k: a.get(k) for k in ("rule", "predicate", "verdict", "confidence",
                                                                 "low_confidence", "wrong")}
                                          for a in (e.get("llm") or {}).get("attempts", [])]}
                            for (t, s), e in sorted(eps.items())],
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("a", type=Path, help="bench result folder A (e.g. --reporter none)")
    p.add_argument("b", type=Path, help="bench result folder B (e.g. --reporter text)")
    args = p.parse_args(argv)
    a, b = episodes(args.a), episodes(args.b)
    both = sorted(set(a) & set(b))
    only_a = [k for k in both if a[k]["success"] and not b[k]["success"]]
    only_b = [k for k in both if b[k]["success"] and not a[k]["success"]]
    print(json.dumps({
        "runs": {str(args.a): digest_run(a), str(args.b): digest_run(b)},
        "paired": {"episodes": len(both), "both": sum(a[k]["success"] and b[k]["success"] for k in both),
                   "only_a": [f"{t} {s}" for t, s in only_a], "only_b": [f"{t} {s}" for t, s in only_b],
                   "p_value": mcnemar_exact(len(only_a), len(only_b))},
    }, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
