"""Cases from a real run (``judge --from RUN_DIR``): the final states its episodes reached.

The synthetic set says how a reporter does on states built to test one condition; a run's final
states are the ones a planner really leaves behind (half-built stacks, a block left on the arm's
path).  Each episode line of ``RUN_DIR/episodes.jsonl`` with ``final_poses`` (every object's
``[x, y, z, qw, qx, qy, qz]`` after the episode's last settle) becomes a case of kind ``run``: its
movable objects are placed on the episode's initial world and settled like every other case, and
its label is the task predicate on *that* state (``detail`` also gives the run's own verdict; the
two differ only if the realised state does, e.g. an object was still held by the suction cup).
"""

from __future__ import annotations

import json
from pathlib import Path

from capmj.errors import ConfigError
from capmj.judge.cases import JudgeCase, Stage, layout_rows
from capmj.sim.state import Pose

__all__ = ["RUN_KIND", "run_cases"]

RUN_KIND = "run"


def run_cases(run_dir: Path) -> tuple[list[JudgeCase], list[str]]:
    """The cases of a run's episodes, and why some episodes gave none."""
    from capmj.tasks.registry import get_task

    path = Path(run_dir) / "episodes.jsonl"
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except FileNotFoundError:
        raise ConfigError(f"--from {run_dir}: no episodes.jsonl; give a result folder of python -m capmj.bench") from None
    cases: list[JudgeCase] = []
    problems: list[str] = []
    stages: dict[tuple[str, int], Stage] = {}
    for n, line in enumerate(lines, start=1):
        try:
            rec = json.loads(line)
        except json.JSONDecodeError:
            problems.append(f"line {n}: not JSON")
            continue
        task, seed, poses = str(rec.get("task")), int(rec.get("seed", -1)), rec.get("final_poses") or {}
        if not poses:
            problems.append(f"line {n} ({task} {seed}): no final_poses")
            continue
        try:
            stage = stages.get((task, seed)) or stages.setdefault((task, seed), Stage(get_task(task), seed))
        except Exception as exc:  # noqa: BLE001 - a task that no longer loads gives no case
            problems.append(f"line {n} ({task} {seed}): {type(exc).__name__}: {exc}")
            continue
        by_name = {o.name: o.obj_id for o in stage.world.objects}
        layout = {by_name[name]: Pose.of(v[:3], v[3:7]) for name, v in poses.items()
                  if name in by_name and by_name[name] in stage.world.movable_ids}
        stored = {int(r[0]): Pose.of(r[1:4], r[4:8]) for r in layout_rows(layout)}
        verdict = stage.evaluate(stage.realise(stored))
        agent = "/".join(str(x) for x in (rec.get("agent"), rec.get("model")) if x)
        cases.append(JudgeCase(task, seed, f"run{n}", RUN_KIND, bool(verdict.success),
                               "" if verdict.success else "; ".join(verdict.diagnostics),
                               f"final state of {agent} in {run_dir} (line {n}; the run's verdict: "
                               f"{'success' if rec.get('success') else 'failure'})", verdict.progress,
                               layout_rows(stored)))
    return cases, problems
