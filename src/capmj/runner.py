"""Run one episode: :func:`run_episode` (task, seed, agent) -> :class:`EpisodeResult`;
:func:`record_episode` runs it and logs it to an ``.rrd`` with :class:`capmj.log.recorder.RerunRecorder`;
:func:`start_episode` is the set-up every episode shares (the bench's, the dm_env's, the judge's).

The runner never raises for an episode's own failure: a task whose scene cannot be generated, a
world that does not compile, an agent that raises or runs out of budget — each becomes a recorded,
explained failed result, so a benchmark grid always completes.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from capmj.agents.attribution import final_poses, placement_drift
from capmj.agents.base import Agent, Budget, EpisodeContext
from capmj.errors import EvaluationFailed, describe, error_facts
from capmj.record import ArrayFrames, NullRecorder, Recorder
from capmj.records import Drift, EpisodeResult, LLMNotes, PerceptionNotes
from capmj.sim.world import World
from capmj.tasks.predicates import ravens_reward
from capmj.tasks.protocol import Scene, Task, make_scene

__all__ = ["FRAME_EVERY_STEPS", "EpisodeResult", "record_episode", "run_episode", "start_episode"]

FRAME_EVERY_STEPS = 25  # 20 Hz of simulated time in logs


def _attach_frames(world: World, recorder: Recorder) -> None:
    """Send the recorder every body's pose now and every FRAME_EVERY_STEPS physics steps: the
    objects, then the robot's bodies.  A recorder taking arrays (:class:`ArrayFrames`) gets one
    copy of MuJoCo's pose arrays per frame, the others a dict of tuples."""
    names = (*(o.body for o in world.objects), *world.link_names)
    ids = world.body_index(names)
    if isinstance(recorder, ArrayFrames):
        def emit(w: World) -> None:
            recorder.frame_arrays(w.time, names, *w.body_poses(ids))
    else:
        def emit(w: World) -> None:
            recorder.frame(w.time, {n: (tuple(p), tuple(q)) for n, p, q in zip(names, *w.body_poses(ids))})

    emit(world)
    world.add_frame_listener(emit, FRAME_EVERY_STEPS)


def start_episode(task: Task, seed: int, *, scene: Scene | None = None, budget: Budget | None = None,
                  recorder: Recorder | None = None) -> EpisodeContext:
    """Set up the episode of (task, seed) and return the agent's context: the scene
    (``make_scene(task, seed)``, or ``scene`` when given), its world compiled and settled, the
    recorder (if any) attached to the world and told the goal, then :class:`EpisodeContext`, which
    snapshots this state as the episode's start.

    Everything that plays or stages an episode starts here, so they all start from the same state.
    Raises what the task or MuJoCo raise (:func:`run_episode` records it as the episode's failure);
    a recorder that cannot attach is told so and the episode goes on.
    """
    rec = recorder or NullRecorder()
    scene = make_scene(task, seed) if scene is None else scene
    world = World(scene.objects)
    world.settle()
    if not isinstance(rec, NullRecorder):
        _attach_frames(world, rec)
        try:
            rec.attach(world)
        except Exception as exc:  # noqa: BLE001 - logging must never change the episode's outcome
            rec.text("log_errors", f"attach failed: {describe(exc)}")
    rec.text("goal", scene.goal)
    return EpisodeContext(task, seed, scene, world, budget=budget, recorder=rec)


def run_episode(task: Task, seed: int, agent: Agent, *, budget: Budget | None = None,
                recorder: Recorder | None = None) -> EpisodeResult:
    """Set up the episode of (task, seed) (:func:`start_episode`), let the agent act, judge the
    settled final state."""
    rec = recorder or NullRecorder()
    t0 = time.perf_counter()
    name = getattr(task, "name", repr(task))
    model = getattr(agent, "model", None)
    try:
        ctx = start_episode(task, seed, budget=budget, recorder=rec)
    except Exception as exc:  # noqa: BLE001 - a broken task fails its own episode only
        rec.text("verdict", f"FAILED before acting: {describe(exc)}")
        kind, why = error_facts(exc)
        return EpisodeResult(name, seed, agent.name, model, False, 0.0, 0.0, 0, 0, 0.0,
                             time.perf_counter() - t0, describe(exc), error_type=kind, error_status=why)
    scene, world = ctx.scene, ctx.world
    error: str | None = None
    error_type: str | None = None
    status: str | None = None
    diags: tuple[str, ...]
    try:
        agent.act(ctx)
    except Exception as exc:  # noqa: BLE001 - recorded as this episode's failure
        error = describe(exc)
        error_type, status = error_facts(exc)
    try:
        verdict = ctx.verdict()
        reward = ravens_reward(task.oracle_goals(scene), world.state())
    except Exception as exc:  # noqa: BLE001
        if error is None:
            error, error_type = f"evaluation failed: {describe(exc)}", EvaluationFailed.__name__
        success, progress, reward, diags = False, 0.0, 0.0, ()
    else:
        success, progress, diags = verdict.success, verdict.progress, verdict.diagnostics
    llm = ctx.notes.get("llm")
    perception = ctx.notes.get("perception")  # rgbd mode: capmj.agents.api.perception_audit
    poses: dict[str, tuple[float, ...]]
    drift: Drift | None
    try:
        poses, drift = final_poses(world), placement_drift(world, ctx.placements)
    except Exception:  # noqa: BLE001 - attribution facts are optional
        poses, drift = {}, None
    rec.text("verdict", ("SUCCESS" if success else "FAILURE") + f" (progress {progress:.2f})\n" + "\n".join(diags)
             + (f"\nerror: {error}" if error else ""))
    return EpisodeResult(name, seed, agent.name, model, success, progress, float(reward), ctx.total_primitives,
                         ctx.attempt + 1, world.time, time.perf_counter() - t0, error, scene.goal, tuple(diags),
                         llm if isinstance(llm, LLMNotes) else None, final_poses=poses, drift=drift,
                         error_type=error_type, error_status=status, calls=tuple(ctx.notes.get("llm_calls", ())),
                         perception=perception if isinstance(perception, PerceptionNotes) else None)


def _oracle_goals(task: Any, seed: int) -> tuple:
    """The task's oracle goals for this seed (where objects should end), or () if they fail."""
    try:
        return tuple(task.oracle_goals(make_scene(task, seed)))
    except Exception:  # noqa: BLE001 - the episode itself reports a broken task
        return ()


def record_episode(task: Any, seed: int, agent: Any, path: str | Path, *, images: bool = False,
                   budget: Budget | None = None) -> EpisodeResult:
    """Run one episode and log it to the ``.rrd`` at ``path`` (summary included); the result has
    ``rrd`` set to the path.  An episode without a log is :func:`run_episode`: one function, one
    contract (this one once did both, by whether ``path`` was None).

    It lives here, not in :mod:`capmj.log`, because it runs the episode; the log package only
    records what it is sent.
    """
    if path is None:
        raise TypeError("record_episode logs to a path; run an episode without a log with run_episode")
    from capmj.log.recorder import RerunRecorder  # rerun is imported only when an episode is logged

    name = getattr(task, "name", str(task))
    rec = RerunRecorder(path, task=name, seed=seed, agent=getattr(agent, "name", None),
                        model=getattr(agent, "model", None), images=images, goals=_oracle_goals(task, seed))
    try:
        result = run_episode(task, seed, agent, budget=budget, recorder=rec)
        result = replace(result, rrd=str(path))
        rec.finish(result)
    finally:
        rec.close()
    return result
