"""Per-episode results and a digest of the final physics state, for behaviour-preserving refactors.

Runs the oracle and the reference agent over (task, seed) and prints one JSON line per episode:
every field of :class:`~capmj.runner.EpisodeResult` except the wall time, plus ``state_sha256`` —
a SHA-256 of the final ``qpos``, ``qvel``, ``act``, simulated time and suction weld data.  Two runs
on different code versions compare with ``diff``: identical lines mean bit-identical episodes.

    python benchmarks/episode_digest.py [--agents oracle,reference] [--tasks benchmark] [--seeds 5] > a.jsonl
"""

from __future__ import annotations

import argparse
import hashlib
import json

import numpy as np

from capmj.agents.base import EpisodeContext
from capmj.runner import run_episode
from capmj.tasks.registry import get_task, resolve


class _Capture:
    """Wraps an agent and keeps the episode's world, so its final state can be digested."""

    def __init__(self, agent) -> None:
        self.agent, self.name, self.model, self.world = agent, agent.name, None, None

    def act(self, ctx: EpisodeContext) -> None:
        self.world = ctx.world
        self.agent.act(ctx)


def state_digest(world) -> str:
    d, m = world.data, world.model
    h = hashlib.sha256()
    for a in (d.qpos, d.qvel, d.act, np.array([d.time]), m.eq_data, d.eq_active):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def _agent(name: str):
    if name == "oracle":
        from capmj.agents.oracle import OracleAgent
        return OracleAgent()
    from capmj.agents.reference import ReferenceAgent
    return ReferenceAgent()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--agents", default="oracle,reference")
    ap.add_argument("--tasks", default="benchmark", help="names, tags or 'all' (default: benchmark)")
    ap.add_argument("--seeds", type=int, default=5, help="number of test seeds (odd, from 10001)")
    args = ap.parse_args(argv)
    seeds = [10001 + 2 * k for k in range(args.seeds)]
    for agent_name in args.agents.split(","):
        for name in resolve(args.tasks):
            task = get_task(name)
            for seed in seeds:
                cap = _Capture(_agent(agent_name))
                res = run_episode(task, seed, cap).to_dict()
                res.pop("wall_s")
                res["state_sha256"] = state_digest(cap.world) if cap.world is not None else None
                print(json.dumps(res, sort_keys=True), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
