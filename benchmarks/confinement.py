"""Which layer stops each hostile fixture, and what confining generated task code costs.

Hostile task modules (``tests/hostile_candidates.py``: the good candidate with one door added):

- ``static``: the static check's verdict, and whether its message names the door;
- ``guarded``: checked with the static check bypassed, the code in the jail with the audit hook;
- ``jail_only``: the same with the hook switched off (as code that reached the interpreter could).

For each run: the layer that stopped it (``guard``: the hook refused an event; ``wire``: what it
sent was not a valid message; ``jail``: it failed against the OS boundary; ``checks``: it ran, and
the checks computed in capmj rejected it; ``harmless``: it ran and was accepted, with no trace
left), the traces it left on the host (must be none), and whether it was accepted.  Hostile plans
(``benchmarks/hostile_plans.py``, run as real ``--agent llm`` episodes) report their layer too.

Costs: seconds per generated candidate (the good candidates through every check, jailed),
milliseconds per confined ``evaluate`` call against the same call in-process, the start of a
jail and of a fresh task process (one per episode), and a benchmark grid (``python -m capmj.bench``, oracle, in-process worker) over
the generated package against the same module installed as an ordinary plugin, run in turn
A B A B … with the median of the pairwise ratios.

    python benchmarks/confinement.py [--repeat 5] [--bench-seeds 10001:10041:2] [--out FILE]

Prints one JSON object (and writes it to ``--out`` if given).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from generated_package import GOOD, install_generated, install_trusted_copy  # noqa: E402
from hostile_candidates import CORPUS, MODULE, NAME, Hostile, run_hostile  # noqa: E402

from capmj.confine.jail import Limits  # noqa: E402
from capmj.confine.proxy import ConfinedTask, ModuleSource  # noqa: E402
from capmj.generate.isolate import run_isolated  # noqa: E402
from capmj.generate.static import static_checks  # noqa: E402

GOOD_FILES = {"good_zone_color.py": "put-blocks-in-zone-of-same-color",
              "good_block_in_bowl.py": "put-named-block-in-named-bowl",
              "good_stack_in_zone.py": "stack-small-on-big-in-zone"}


def _static(h: Hostile) -> dict[str, Any]:
    code = h.module(Path("/nonexistent/marker"), Path("/nonexistent/victim"), 9)
    bad = next((r for r in static_checks(code) if r.outcome == "fail"), None)
    return {"rejected": bad is not None, "check": bad.name if bad else None,
            "names_the_door": bool(bad and h.static in bad.detail), "detail": bad.detail[:200] if bad else None}


def _layer(run: Any, traces: list[str]) -> str:
    failed = next((r for r in run.results if r.outcome in ("fail", "error")), None)
    if run.violation is not None:
        return "guard"
    if failed is not None and "WireError" in failed.detail:
        return "wire"
    if failed is not None and failed.name == "load":
        return "jail"
    if failed is not None:
        return "checks"
    return "harmless" if not traces else "NOT STOPPED"


def _attempt(h: Hostile, guarded: bool) -> dict[str, Any]:
    with tempfile.TemporaryDirectory(prefix="capmj-hostile-") as tmp:
        run, traces = run_hostile(h, Path(tmp), guarded=guarded)
    failed = next((r for r in run.results if r.outcome in ("fail", "error")), None)
    return {"stopped_by": _layer(run, traces), "event": (run.violation or {}).get("event"),
            "first_failure": f"{failed.name}: {failed.detail[:140]}" if failed else None, "traces": traces,
            "accepted": failed is None and run.violation is None}


def _candidate_seconds(repeat: int) -> dict[str, Any]:
    from generator_script import CANDIDATES

    out = {}
    for file, name in GOOD_FILES.items():
        code = (CANDIDATES / file).read_text()
        walls, passed = [], True
        for _ in range(repeat):
            run = run_isolated(ModuleSource(f"capmj_generated_bench.{name.replace('-', '_')}", code), name=name,
                               seeds=(0, 1), accept_rate=1.0, tags=("generated-by-llm",), limits=Limits())
            walls.append(run.wall_s)
            passed &= all(r.passed for r in run.results)
        out[file] = {"accepted_by_checks": passed, "seconds_median": round(statistics.median(walls), 3),
                     "processes": run.jail["processes"] if run.jail else None}
    return out


def _evaluate_ms(calls: int) -> dict[str, Any]:
    import importlib.util

    from capmj.sim.state import SceneState
    from capmj.tasks.protocol import make_scene
    from generator_script import CANDIDATES

    spec = importlib.util.spec_from_file_location("good_here", CANDIDATES / "good_zone_color.py")
    assert spec is not None and spec.loader is not None
    here = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(here)
    task = ConfinedTask(ModuleSource(MODULE, GOOD))
    t0 = time.perf_counter()
    task.load()
    load_s = time.perf_counter() - t0
    scene = make_scene(task, 10001)
    state = SceneState.from_specs(scene.objects)
    timings: dict[str, list[float]] = {"jailed": [], "in_process": []}
    for _ in range(calls):
        for key, t in (("jailed", task), ("in_process", here.TASK)):
            t0 = time.perf_counter()
            t.evaluate(scene, state)
            timings[key].append(time.perf_counter() - t0)
    fresh = []
    for seed in range(20):  # a fresh task process per episode: the fork, the module's load, one scene
        task.new_episode()
        t0 = time.perf_counter()
        make_scene(task, seed)
        fresh.append(time.perf_counter() - t0)
    task.close()
    return {"calls": calls, "jailed_ms_median": round(1000 * statistics.median(timings["jailed"]), 3),
            "in_process_ms_median": round(1000 * statistics.median(timings["in_process"]), 3),
            "jail_start_s": round(load_s, 3), "fresh_task_process_ms_median": round(1000 * statistics.median(fresh), 2)}


def _bench_wall(seeds: str, repeat: int) -> dict[str, Any]:
    with tempfile.TemporaryDirectory(prefix="capmj-bench-confine-") as tmp:
        root = Path(tmp)
        sites = {"generated": install_generated(root), "built_in": install_trusted_copy(root)}
        walls: dict[str, list[float]] = {k: [] for k in sites}
        episodes: dict[str, list[Any]] = {}
        for i in range(repeat + 1):  # the first pair warms caches and is not counted
            for kind, site in sites.items():
                env = {**os.environ, "PYTHONPATH": str(site)}
                env.pop("CAPMJ_DISABLE_PLUGINS", None)
                out = root / f"run-{kind}-{i}"
                t0 = time.perf_counter()
                r = subprocess.run([sys.executable, "-m", "capmj.bench", "--tasks", NAME, "--seeds", seeds, "--agent",
                                    "oracle", "--workers", "0", "--no-log", "--no-progress", "--out", str(out)],
                                   capture_output=True, text=True, env=env, timeout=1800)
                wall = time.perf_counter() - t0
                if r.returncode != 0:
                    raise RuntimeError(r.stderr[-2000:])
                rows = [json.loads(x) for x in (out / "episodes.jsonl").read_text().splitlines()]
                episodes[kind] = [(e["seed"], e["success"], e.get("error_type")) for e in rows]
                if i:
                    walls[kind].append(wall)
    ratios = [g / b for g, b in zip(walls["generated"], walls["built_in"])]
    return {"seeds": seeds, "pairs": repeat, "wall_s_median": {k: round(statistics.median(v), 2) for k, v in walls.items()},
            "ratio_median": round(statistics.median(ratios), 3), "ratio_min": round(min(ratios), 3),
            "ratio_max": round(max(ratios), 3), "same_results": episodes["generated"] == episodes["built_in"],
            "episodes": episodes["generated"]}


def _plans() -> list[dict[str, Any]]:
    """The rows of ``benchmarks/hostile_plans.py`` (loaded by path: ``tests/hostile_plans.py``, its
    fixtures, has the same module name)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("hostile_plans_benchmark", ROOT / "benchmarks" / "hostile_plans.py")
    assert spec is not None and spec.loader is not None
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    return [{k: row.get(k) for k in ("fixture", "stopped_by", "error", "peak_mb")} for row in bench.run_hostile_plans()]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="timing runs per measurement")
    ap.add_argument("--bench-seeds", default="10001:10041:2", help="seeds of the paired bench grid")
    ap.add_argument("--evaluate-calls", type=int, default=500)
    ap.add_argument("--out", type=Path, help="also write the JSON here")
    args = ap.parse_args()
    rows = []
    for h in CORPUS:
        rows.append({"id": h.id, "door": h.door, "static": _static(h), "guarded": _attempt(h, True),
                     "jail_only": _attempt(h, False)})
        print(f"{h.id}: static={rows[-1]['static']['check']} guarded={rows[-1]['guarded']['stopped_by']} "
              f"jail_only={rows[-1]['jail_only']['stopped_by']}", file=sys.stderr, flush=True)
    plans = _plans()
    costs = {"candidate": _candidate_seconds(args.repeat), "evaluate": _evaluate_ms(args.evaluate_calls),
             "bench": _bench_wall(args.bench_seeds, args.repeat)}

    def count(key: str, layer: str) -> int:
        return sum(r[key]["stopped_by"] == layer for r in rows)

    layers = ("guard", "wire", "jail", "checks", "harmless", "NOT STOPPED")
    total = {
        "modules": len(rows),
        "static_rejected": sum(r["static"]["rejected"] for r in rows),
        "static_names_the_door": sum(r["static"]["names_the_door"] for r in rows),
        "guarded_by_layer": {k: count("guarded", k) for k in layers},
        "jail_only_by_layer": {k: count("jail_only", k) for k in layers},
        "traces_on_host": sum(bool(r[k]["traces"]) for r in rows for k in ("guarded", "jail_only")),
        "hostile_accepted_guarded": [r["id"] for r in rows if r["guarded"]["accepted"]],
        "plans": len(plans), "plans_by_layer": {k: sum(p.get("stopped_by") == k for p in plans)
                                               for k in sorted({str(p.get("stopped_by")) for p in plans})},
        "seconds_per_candidate_median": statistics.median(c["seconds_median"] for c in costs["candidate"].values()),
        "evaluate_ms_median": costs["evaluate"]["jailed_ms_median"],
        "bench_ratio_median": costs["bench"]["ratio_median"],
        "load_avg": os.getloadavg()[0],
    }
    out = {"total": total, "costs": costs, "corpus": rows, "plans": plans}
    text = json.dumps(out, indent=1)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
