"""Episode-log size benchmark: bytes per ``.rrd`` without images, per task, for oracle episodes.

Prints one JSON line: per-episode sizes (kB), primitives and simulated seconds, and the share of
the file that is the stored viewer layout.  The target is <= 250 kB per episode without images.

    python benchmarks/rrd_size.py [--tasks benchmark] [--seeds 10001,10003] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

TARGET_KB = 250


def _blueprint_bytes(out: Path) -> int:
    """Size of a file that holds only the stored layout (the same in every episode)."""
    import rerun as rr

    from capmj.log.blueprint import episode_blueprint

    p = out / "layout-only.rrd"
    rec = rr.RecordingStream("capmj", recording_id="layout-only")
    rec.save(str(p), write_footer=False)
    rec.send_blueprint(episode_blueprint(), make_active=True, make_default=True)
    rec.flush()
    rec.disconnect()
    return p.stat().st_size


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", default="benchmark", help="task names or tags, comma-separated")
    ap.add_argument("--seeds", default="10001,10003")
    ap.add_argument("--out", type=Path, default=None, help="keep the .rrd files here (default: a temp dir)")
    args = ap.parse_args()

    from capmj.agents.oracle import OracleAgent
    from capmj.runner import record_episode
    from capmj.tasks.registry import get_task, resolve

    out = args.out or Path(tempfile.mkdtemp(prefix="capmj-rrd-size-"))
    out.mkdir(parents=True, exist_ok=True)
    seeds = [int(s) for s in args.seeds.split(",")]
    episodes = []
    t0 = time.perf_counter()
    for task in map(get_task, resolve(args.tasks)):
        for seed in seeds:
            p = out / f"{task.name}-{seed}.rrd"
            r = record_episode(task, seed, OracleAgent(), p)
            episodes.append({"task": task.name, "seed": seed, "success": r.success, "primitives": r.primitives,
                             "sim_s": round(r.sim_s, 2), "kB": round(p.stat().st_size / 1000, 1)})
    sizes = [e["kB"] for e in episodes]
    print(json.dumps({
        "benchmark": "rrd_size", "agent": "oracle", "images": False, "episodes": len(episodes),
        "kB_mean": round(sum(sizes) / len(sizes), 1), "kB_min": min(sizes), "kB_max": max(sizes),
        "target_kB": TARGET_KB, "over_target": sum(s > TARGET_KB for s in sizes),
        "layout_kB": round(_blueprint_bytes(out) / 1000, 1),
        "wall_s": round(time.perf_counter() - t0, 1), "per_episode": episodes,
    }))


if __name__ == "__main__":
    main()
