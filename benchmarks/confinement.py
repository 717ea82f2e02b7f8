"""Which layer stops each door of the hostile-candidate corpus, the traces left, and what the guard costs.

For every module of ``tests/hostile_candidates.py`` (fixtures: the good candidate with one door
to the operating system added) it runs the static check, then the real check worker three times
with the static check bypassed: runtime guard alone, OS layer alone, both.  After each run it
looks for the door's traces (the marker file, the victim file gone, a connection to a listening
socket, a process still running from the run's folder).  Then the three good hand-written
candidates go through all checks with both layers (acceptance must be unchanged) and
``--repeat`` times with and without the guard, to time what the audit hook adds.

    python benchmarks/confinement.py [--repeat 5] [--out benchmarks/results/confinement.json]

Prints one JSON object (and writes it to ``--out`` if given).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from hostile_candidates import CORPUS, Hostile, run_hostile  # noqa: E402

from capmj.generate.config import Limits  # noqa: E402
from capmj.generate.isolate import run_isolated  # noqa: E402
from capmj.generate.static import static_checks  # noqa: E402

GOOD = {"good_zone_color.py": "put-blocks-in-zone-of-same-color", "good_block_in_bowl.py": "put-named-block-in-named-bowl",
        "good_stack_in_zone.py": "stack-small-on-big-in-zone"}
LAYERS = {"guard_only": {"os_layer": False}, "os_layer_only": {"guarded": False}, "both": {}}


def _attempt(h: Hostile, layers: dict[str, bool]) -> dict[str, object]:
    with tempfile.TemporaryDirectory(prefix="capmj-hostile-") as tmp:
        run, traces = run_hostile(h, Path(tmp), **layers)
    failed = next((r for r in run.results if r.outcome in ("fail", "error")), None)
    return {"event": (run.violation or {}).get("event"), "check": (run.violation or {}).get("check"),
            "stopped": run.violation is not None or not traces and failed is not None,
            "first_failure": failed.detail[:160] if failed else None, "traces": traces, "os_layer": run.os_layer}


def _static(h: Hostile) -> dict[str, object]:
    code = h.module(Path("/nonexistent/marker"), Path("/nonexistent/victim"), 9)
    bad = next((r for r in static_checks(code) if r.outcome == "fail"), None)
    return {"rejected": bad is not None, "check": bad.name if bad else None,
            "names_the_door": bool(bad and h.static in bad.detail), "detail": bad.detail[:200] if bad else None}


def _good(file: str, name: str, repeat: int) -> dict[str, object]:
    path = ROOT / "tests" / "generator_candidates" / file
    static_ok = all(r.passed for r in static_checks(path.read_text()))
    kw = {"name": name, "seeds": (0, 1), "accept_rate": 1.0, "tags": ("generated-by-llm",), "limits": Limits()}
    both = run_isolated(path, **kw)
    walls: dict[str, list[float]] = {"guarded": [], "unguarded": []}
    for _ in range(repeat):  # interleaved, so load drift hits both alike
        walls["guarded"].append(run_isolated(path, os_layer=False, **kw).wall_s)
        walls["unguarded"].append(run_isolated(path, os_layer=False, guarded=False, **kw).wall_s)
    med = {k: statistics.median(v) for k, v in walls.items()}
    return {"accepted_by_checks": static_ok and all(r.passed for r in both.results), "os_layer": both.os_layer,
            "wall_s_median": {k: round(v, 3) for k, v in med.items()},
            "guard_adds_s": round(med["guarded"] - med["unguarded"], 3),
            "guard_adds_pct": round(100 * (med["guarded"] / med["unguarded"] - 1), 1)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="timing runs per good candidate and mode")
    ap.add_argument("--out", type=Path, help="also write the JSON here")
    args = ap.parse_args()
    rows = []
    for h in CORPUS:
        rows.append({"id": h.id, "door": h.door, "where": h.where, "static": _static(h),
                     **{k: _attempt(h, v) for k, v in LAYERS.items()}})
        print(f"{h.id}: static={rows[-1]['static']['check']} guard={rows[-1]['guard_only']['event']} "
              f"os={rows[-1]['os_layer_only']['traces']}", file=sys.stderr, flush=True)
    good = {f: _good(f, n, args.repeat) for f, n in GOOD.items()}
    total = {
        "modules": len(rows),
        "static_rejected": sum(r["static"]["rejected"] for r in rows),
        "static_names_the_door": sum(r["static"]["names_the_door"] for r in rows),
        **{f"{k}_stopped": sum(bool(r[k]["stopped"]) for r in rows) for k in LAYERS},
        **{f"{k}_traces": sum(bool(r[k]["traces"]) for r in rows) for k in LAYERS},
        "not_stopped_by_guard": [r["id"] for r in rows if not r["guard_only"]["stopped"]],
        "good_accepted": sum(bool(g["accepted_by_checks"]) for g in good.values()),
        "guard_adds_s_median": statistics.median(float(g["guard_adds_s"]) for g in good.values()),  # type: ignore[arg-type]
        "load_avg": os.getloadavg()[0],
    }
    out = {"total": total, "good": good, "corpus": rows}
    text = json.dumps(out, indent=1)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
