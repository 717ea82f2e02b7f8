"""LLM-grid throughput: episodes per minute against a model that answers after a fixed latency.

The "model" is the stub server (tests/llm_stub_server.py) answering every planner request for task
A with a plan that solves it (tests/stub_solver.py) after ``latency`` seconds, so each episode is
one LLM wait plus real sandbox, API and physics work.  For each latency the grid runs with
``--workers W`` and ``--concurrency`` 1, 4, 16 (and optionally ``--executor ray``); episodes per
configuration scale with the episodes in flight so the pipeline is full.  Peak memory is the
largest summed RSS of this process and its children, sampled every 0.2 s.  Prints one JSON object.

    python benchmarks/llm_throughput.py                       # latencies 0.5 2 8, concurrency 1 4 16
    python benchmarks/llm_throughput.py --latency 2 --concurrency 1 4 --ray
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from llm_stub_server import StubLLMServer  # noqa: E402
from stub_solver import TASK, solver  # noqa: E402

from capmj.bench.cli import main as bench  # noqa: E402


def _tree_rss(root: int) -> int:
    """Summed resident memory (bytes) of ``root`` and all its descendants, from /proc."""
    parent: dict[int, int] = {}
    rss: dict[int, int] = {}
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            stat = Path(f"/proc/{d}/stat").read_text().rsplit(")", 1)[1].split()
            parent[int(d)] = int(stat[1])
            rss[int(d)] = int(stat[21]) * os.sysconf("SC_PAGE_SIZE")
        except (OSError, IndexError, ValueError):
            continue
    total, todo, seen = 0, [root], set()
    while todo:
        pid = todo.pop()
        if pid in seen:
            continue
        seen.add(pid)
        total += rss.get(pid, 0)
        todo.extend(c for c, p in parent.items() if p == pid)
    return total


class PeakMemory:
    def __init__(self) -> None:
        self.peak = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.wait(0.2):
            self.peak = max(self.peak, _tree_rss(os.getpid()))

    def __enter__(self) -> "PeakMemory":
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()


def run_one(server: StubLLMServer, latency: float, workers: int, concurrency: int, executor: str) -> dict:
    n = max(8, 2 * workers * concurrency)
    seeds = f"10001:{10001 + 2 * n}:2"
    out = Path(tempfile.mkdtemp(prefix="capmj-throughput-")) / "run"
    server.respond_with(solver(latency))
    calls0 = len(server.requests)
    args = ["--agent", "llm", "--model", "openai/stub", "--api-base", server.base_url, "--reporter", "none",
            "--tasks", TASK, "--seeds", seeds, "--out", str(out), "--workers", str(workers),
            "--concurrency", str(concurrency), "--executor", executor, "--no-log", "--no-progress"]
    with PeakMemory() as mem:
        t0 = time.perf_counter()
        rc = bench(args)
        wall = time.perf_counter() - t0
    lines = [json.loads(x) for x in (out / "episodes.jsonl").read_text().splitlines() if x.strip()]
    return {"latency_s": latency, "executor": executor, "workers": workers, "concurrency": concurrency,
            "episodes": len(lines), "exit_code": rc, "successes": sum(bool(r["success"]) for r in lines),
            "llm_calls": len(server.requests) - calls0, "wall_s": round(wall, 2),
            "episodes_per_min": round(60 * len(lines) / wall, 1), "peak_rss_mb": round(mem.peak / 2**20)}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--latency", type=float, nargs="+", default=[0.5, 2.0, 8.0])
    p.add_argument("--concurrency", type=int, nargs="+", default=[1, 4, 16])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--ray", action="store_true", help="also run each configuration with --executor ray")
    a = p.parse_args()
    os.environ.pop("CAPMJ_LLM_CACHE", None)  # every request must reach the server
    rows = []
    with StubLLMServer() as server:
        for latency in a.latency:
            for k in a.concurrency:
                for executor in ("local", "ray") if a.ray else ("local",):
                    row = run_one(server, latency, a.workers, k, executor)
                    print(json.dumps(row), file=sys.stderr)
                    rows.append(row)
    base = {r["latency_s"]: r["episodes_per_min"] for r in rows if r["concurrency"] == 1 and r["executor"] == "local"}
    for r in rows:
        b = base.get(r["latency_s"])
        r["speedup_vs_concurrency_1"] = round(r["episodes_per_min"] / b, 2) if b else None
    print(json.dumps({"task": TASK, "cpus": os.cpu_count(), "load_avg_at_end": os.getloadavg(), "runs": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
