"""A task process: the only code that runs generated task code, one fresh process per episode.

Forked inside the jail by :mod:`capmj.confine.forkserver` (which has imported the task API and
whose child has installed the seccomp filter: no process, no program, no socket), it answers
frames (:mod:`capmj.confine.wire`) relayed by the fork server:

1. ``load``: the module's exact text and its final module name (the name it has once installed,
   so nothing distinguishes a check from a later run).  The audit-hook guard is installed first
   when asked (an early, explained rejection of what the static check missed; the jail is the
   boundary, not the guard — the parent may switch it off to measure the jail alone).  The text is
   compiled from the string — never from a file, so no ``.pyc`` is ever read — and run; the answer
   is the task's facts: name, tags, docstring and which protocol methods it has.
2. Calls: ``sample_scene`` (with the PCG64 state of the caller's generator, returning the scene and
   the advanced state), ``oracle_goals`` and ``evaluate``; each answer is data, or an error with the
   exception's class, message and a traceback tail.

A scene this process sampled is kept by its wire text, so a later call about it hands the task
the very object it made (``info`` keys that JSON would turn into strings stay what the task wrote).
"""

from __future__ import annotations

import inspect
import json
import sys
import traceback
from types import ModuleType
from typing import IO, Any, Callable

from capmj.confine import wire

OPS = ("load", "sample_scene", "oracle_goals", "evaluate")
"""The requests a task process answers."""
PRECOMPILED: dict[str, tuple[str, Any]] = {}
"""Module name -> (text, code object) compiled by the fork server before it forked this process."""
_KEPT_SCENES = 64
CANDIDATE_FILE = "<generated task>"
"""The file name the module's code carries (in tracebacks, and for the guard: code from here is the task's)."""


def _error(e: BaseException) -> dict[str, Any]:
    tb = traceback.format_exc()
    return {"error": {"type": type(e).__name__, "message": str(e)[:1000], "traceback": tb[-1500:]}}


def _facts(task: Any) -> dict[str, Any]:
    from capmj.tasks.scene_method import DEPRECATED_SCENE_METHOD, SCENE_METHOD

    tags = getattr(task, "tags", None)
    new, old = getattr(task, SCENE_METHOD, None), getattr(task, DEPRECATED_SCENE_METHOD, None)
    return {"name": getattr(task, "name", None) if isinstance(getattr(task, "name", None), str) else None,
            "tags": sorted(tags) if isinstance(tags, (set, frozenset)) and all(isinstance(t, str) for t in tags)
            else None,  # malformed: the parent's validation says so
            "doc": (inspect.getdoc(task) or "")[: wire.MAX_DOC],
            "methods": {SCENE_METHOD: callable(new), DEPRECATED_SCENE_METHOD: callable(old),
                        "aliased": callable(new) and old is not None and old == new,
                        "oracle_goals": callable(getattr(task, "oracle_goals", None)),
                        "evaluate": callable(getattr(task, "evaluate", None))}}


class Host:
    """The loaded task and the scenes it sampled; one method per request."""

    def __init__(self, guard: Callable[[], Any]) -> None:
        self.task: Any = None
        self.scenes: dict[str, Any] = {}
        self._guard = guard

    def load(self, msg: dict[str, Any]) -> dict[str, Any]:
        if self.task is not None:
            raise RuntimeError("a module is already loaded in this process")
        name, text = str(msg["module"]), str(msg["text"])
        if msg.get("guard", True):
            self._guard()
        module = ModuleType(name)
        module.__file__ = CANDIDATE_FILE
        sys.modules[name] = module
        known = PRECOMPILED.get(name)
        code = known[1] if known is not None and known[0] == text else compile(text, CANDIDATE_FILE, "exec")
        exec(code, module.__dict__)  # noqa: S102 - inside the jail, by design
        if not hasattr(module, "TASK"):
            raise AttributeError("the module defines no TASK object (end it with TASK = YourTask())")
        task = module.TASK
        self.task = task() if inspect.isclass(task) else task
        return {"facts": _facts(self.task)}

    def _scene(self, v: Any) -> Any:
        key = json.dumps(v, sort_keys=True)
        return self.scenes.get(key) or wire.scene_from_wire(v)

    def sample_scene(self, msg: dict[str, Any]) -> dict[str, Any]:
        import numpy as np

        from capmj.tasks.protocol import Resample
        from capmj.tasks.scene_method import scene_sampler

        rng = np.random.Generator(np.random.PCG64())
        rng.bit_generator.state = wire.rng_from_wire(msg["rng"])
        try:
            scene = scene_sampler(self.task)(rng)
        except Resample:
            return {"resample": True, "rng": wire.rng_to_wire(rng)}
        from capmj.tasks.protocol import Scene

        if not isinstance(scene, Scene):
            raise TypeError(f"the scene method returned {type(scene).__name__}, not a Scene")
        try:
            data = wire.scene_to_wire(scene)
            json.dumps(data, allow_nan=False)
        except (TypeError, ValueError) as e:
            raise TypeError(f"scene.info is not JSON-serialisable ({e})") from None
        if len(self.scenes) < _KEPT_SCENES:  # keyed as the parent will send it back
            self.scenes[json.dumps(wire.scene_to_wire(wire.scene_from_wire(json.loads(json.dumps(data)))),
                                   sort_keys=True)] = scene
        return {"scene": data, "rng": wire.rng_to_wire(rng)}

    def oracle_goals(self, msg: dict[str, Any]) -> dict[str, Any]:
        from capmj.tasks.protocol import OracleGoal

        goals = list(self.task.oracle_goals(self._scene(msg["scene"])))
        bad = [type(g).__name__ for g in goals if not isinstance(g, OracleGoal)]
        if bad:
            raise TypeError(f"oracle_goals must return OracleGoal steps, got {', '.join(sorted(set(bad)))}")
        return {"goals": [wire.goal_to_wire(g) for g in goals]}

    def evaluate(self, msg: dict[str, Any]) -> dict[str, Any]:
        from capmj.tasks.protocol import Verdict

        v = self.task.evaluate(self._scene(msg["scene"]), wire.state_from_wire(msg["state"]))
        if not isinstance(v, Verdict):
            raise TypeError(f"evaluate must return a Verdict, got {type(v).__name__}")
        return {"verdict": wire.verdict_to_wire(v)}


def serve(inp: IO[bytes], out: IO[bytes]) -> None:
    """Answer frames on ``inp``/``out`` until the channel closes (the task process's whole life).

    Runs in a fresh child of :mod:`capmj.confine.forkserver`, which has installed the seccomp
    filter; the guard is installed by ``load`` when the parent asks for it.
    """
    from capmj.confine import guard

    def report(event: dict[str, Any]) -> None:
        v = event["violation"]
        wire.write_frame(out, {"violation": {"event": str(v["event"]), "detail": str(v["detail"])[:400]}})

    host = Host(lambda: guard.install(CANDIDATE_FILE, report))
    while True:
        try:
            msg = wire.read_frame(inp, wire.MAX_TO_JAIL)
        except wire.WireError:
            return  # the fork server closed the channel
        op = msg.get("op")
        try:
            answer = getattr(host, str(op))(msg) if op in OPS \
                else {"error": {"type": "WireError", "message": f"unknown op {op!r}", "traceback": ""}}
        except BaseException as e:  # noqa: BLE001 - the task's failure is the answer
            answer = _error(e)
        try:
            wire.write_frame(out, answer)
        except (TypeError, ValueError) as e:  # an answer that is not JSON (a task's odd values)
            wire.write_frame(out, _error(e))


__all__ = ["CANDIDATE_FILE", "Host", "OPS", "PRECOMPILED", "serve"]
