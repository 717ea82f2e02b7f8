"""The generator's acceptance pipeline on hand-written candidate task files, through the stub server.

Every file of ``tests/generator_candidates/`` (good and subtly broken ones, each naming the stage
and check that must reject it on its first line) is answered by the local OpenAI-compatible stub
server (``tests/llm_stub_server.py``; scripted answers are fixtures) as one candidate of a single
bottom-up run.  The repair round answers the same code again (a broken candidate stays broken).
Prints one JSON object: per candidate the expected and actual verdict (stage, check), whether
they agree, the oracle rate and the wall time of its checks; then totals.

    python benchmarks/generator_checks.py [--seeds 5] [--accept-rate 0.8] [--workers 2]

Wall times are noisy on a shared machine: read them with the load average printed beside them.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from generator_script import GeneratorScript, all_candidates  # noqa: E402
from llm_stub_server import StubLLMServer  # noqa: E402

from capmj.generate import GenerateConfig, Limits, generate  # noqa: E402


def _verdict(rec) -> tuple[str, str | None]:  # noqa: ANN001
    if rec.accepted:
        return "accepted", None
    last = max((c["attempt"] for c in rec.checks), default=1)
    bad = next((c["name"] for c in rec.checks if c["attempt"] == last and c["outcome"] in ("fail", "error")), None)
    return rec.stage, bad


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--accept-rate", type=float, default=0.8)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cpu-limit", type=int, default=30, help="CPU seconds per check worker (the endless loop's cost)")
    args = ap.parse_args(argv)
    cands = all_candidates()
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp, StubLLMServer(responder=GeneratorScript(cands)) as server:
        cfg = GenerateConfig(mode="bottom-up", model="openai/stub", api_base=server.base_url, out=Path(tmp) / "out",
                             n=len(cands), seeds=args.seeds, accept_rate=args.accept_rate, workers=args.workers,
                             package="capmj-generated-bench", limits=Limits(cpu_s=args.cpu_limit, wall_s=600))
        result = generate(cfg)
        http_calls = len(server.requests)
    wall = time.perf_counter() - t0
    rows = []
    for c, rec in zip(cands, result.records):
        stage, check = _verdict(rec)
        rows.append({"file": c.file, "expected": c.expect, "got": stage + (f":{check}" if check else ""),
                     "ok": (stage, check) == (c.expect_stage, c.expect_check), "oracle_rate": rec.oracle_rate,
                     "checks_wall_s": rec.wall_s.get("checks"), "repaired": rec.repaired})
    good = [r for r in rows if r["expected"] == "accepted"]
    checked = [r["checks_wall_s"] for r in rows if r["checks_wall_s"]]
    print(json.dumps({
        "candidates": len(rows), "good": len(good), "broken": len(rows) - len(good),
        "all_verdicts_right": all(r["ok"] for r in rows),
        "good_accepted": sum(r["got"] == "accepted" for r in good),
        "broken_rejected_at_right_check": sum(r["ok"] for r in rows if r not in good),
        "seeds": args.seeds, "accept_rate": args.accept_rate, "workers": args.workers, "cpu_limit_s": args.cpu_limit,
        "checks_wall_s": {"median": round(statistics.median(checked), 2) if checked else None,
                          "max": round(max(checked), 2) if checked else None},
        "run_wall_s": round(wall, 1), "http_calls": http_calls, "load_average_1min": round(os.getloadavg()[0], 1),
        "per_candidate": rows,
    }, indent=1))
    return 0 if all(r["ok"] for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
