"""A generated task as capmj sees it: a :class:`ConfinedTask` that forwards each protocol call to a
jailed process and believes only validated data.

capmj never imports generated code.  :class:`ConfinedTask` holds the module's exact text and
final module name (:class:`ModuleSource`) and implements the task protocol by asking a jailed
:mod:`capmj.confine.host`: ``sample_scene`` sends the caller's generator state and sets the
advanced state it gets back (a seed still maps to exactly one scene, as in-process), and the
scene, goals and verdict come back through :mod:`capmj.confine.wire`.  The physics, the oracle,
every check and every record stay in capmj's process; the jail only answers questions.

**A fresh process per episode.**  Once a process has answered ``oracle_goals`` or ``evaluate``,
the next ``sample_scene`` — the start of the next episode — goes to a new process, so state a
task keeps between calls (a call counter, a patched module) never outlives one episode.  To keep
that cheap, a spare process is started (and loads the module) while the current one works.

**Facts.**  A loaded task states its name, tags, docstring and protocol methods.  For an
installed package the manifest holds the facts accepted at generation (``expected``); a process
that states other facts is refused with :class:`~capmj.errors.ConfinementError`.  Reading the
facts from the manifest starts no process, so listing tasks never runs generated code.
"""

from __future__ import annotations

import hashlib
import os
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time
import weakref
from dataclasses import dataclass, field
from typing import IO, Any, Callable, Mapping, Sequence

import numpy as np

from capmj.confine import jail, wire
from capmj.confine.guard import VIOLATION_EXIT
from capmj.errors import ConfinedTaskError, ConfinementError, GuardRefused
from capmj.sim.state import SceneState
from capmj.tasks.protocol import OracleGoal, Scene, Verdict
from capmj.tasks.scene_method import DEPRECATED_SCENE_METHOD, SCENE_METHOD

HOST = ("-I", "-B", "-m", "capmj.confine.host")
"""How the jailed interpreter is started (isolated mode: no environment, no user site, no cwd on
the path; ``-B``: it writes no bytecode)."""
_FACT_ATTRIBUTES = frozenset({"name", "tags", SCENE_METHOD, DEPRECATED_SCENE_METHOD, "oracle_goals", "evaluate"})
"""Attributes that come from the task's facts (set by ``_present``)."""
MAX_STDERR = 4_000
"""The tail of a jailed process's stderr that an error message quotes (characters)."""


@dataclass(frozen=True)
class ModuleSource:
    """The exact text of one generated module and the dotted name it runs under."""

    module: str
    text: str

    @property
    def sha256(self) -> str:
        return hashlib.sha256(self.text.encode()).hexdigest()


@dataclass(frozen=True)
class TaskFacts:
    """What a task states about itself: name, tags, docstring, and which protocol methods it has
    (``sample_scene``, ``generate``, ``aliased`` when both are one function, ``oracle_goals``,
    ``evaluate``)."""

    name: str | None
    tags: tuple[str, ...] | None
    doc: str
    methods: Mapping[str, bool] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "tags": None if self.tags is None else list(self.tags), "doc": self.doc,
                "methods": dict(self.methods)}

    @classmethod
    def from_dict(cls, v: Any) -> TaskFacts:
        """Validated facts (from the jail or a manifest); :class:`~capmj.confine.wire.WireError` if malformed."""
        if not isinstance(v, dict):
            raise wire.WireError("facts: expected an object")
        name, tags, doc, methods = v.get("name"), v.get("tags"), v.get("doc", ""), v.get("methods", {})
        if name is not None and (not isinstance(name, str) or len(name) > 200):
            raise wire.WireError("facts.name: expected a string of at most 200 characters")
        if tags is not None and (not isinstance(tags, list) or len(tags) > wire.MAX_TAGS
                                 or not all(isinstance(t, str) and len(t) <= 100 for t in tags)):
            raise wire.WireError(f"facts.tags: expected at most {wire.MAX_TAGS} strings")
        if not isinstance(doc, str) or len(doc) > wire.MAX_DOC:
            raise wire.WireError(f"facts.doc: expected a string of at most {wire.MAX_DOC} characters")
        if not isinstance(methods, dict) or not all(isinstance(k, str) and isinstance(b, bool) for k, b in methods.items()):
            raise wire.WireError("facts.methods: expected an object of booleans")
        return cls(name, None if tags is None else tuple(tags), doc, {k: methods[k] for k in sorted(methods)[:8]})


def _why_ended(returncode: int | None, limits: jail.Limits, timed_out: bool) -> str:
    if timed_out:
        return f"killed: wall-clock limit of {limits.wall_s:g} s exceeded"
    if returncode is not None and returncode > 128:  # bwrap reports a child killed by a signal as 128 + signal
        sig = returncode - 128
        if sig in (signal.SIGXCPU, signal.SIGKILL):
            return f"killed: CPU-time limit of {limits.cpu_s} s exceeded ({signal.Signals(sig).name})"
        return f"killed by signal {signal.Signals(sig).name}" if sig in signal.valid_signals() else f"exit {returncode}"
    if returncode == VIOLATION_EXIT:
        return "ended by the runtime guard"
    return f"the jailed process exited with code {returncode}"


class _Jailed:
    """One jailed host process and its frame channel."""

    def __init__(self, source: ModuleSource, limits: jail.Limits, guard: bool) -> None:
        self.limits = limits
        self.stderr: IO[bytes] = tempfile.TemporaryFile(prefix="capmj-jail-")  # noqa: SIM115 - closed in close()
        self.proc = jail.start([sys.executable, *HOST], limits, self.stderr)
        self.calls = 0
        self.facts: TaskFacts | None = None
        self._send({"op": "load", "module": source.module, "text": source.text, "guard": guard})

    @property
    def pid(self) -> int:
        return self.proc.pid

    def _send(self, message: Mapping[str, Any]) -> None:
        assert self.proc.stdin is not None
        try:
            wire.write_frame(self.proc.stdin, message)
        except (BrokenPipeError, OSError):
            pass  # the process is gone; the read that follows says why

    def _read_exact(self, n: int, deadline: float) -> bytes:
        assert self.proc.stdout is not None
        fd, chunks, got = self.proc.stdout.fileno(), [], 0
        while got < n:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise TimeoutError
            chunk = os.read(fd, min(n - got, 1 << 16))
            if not chunk:
                raise EOFError
            chunks.append(chunk)
            got += len(chunk)
        return b"".join(chunks)

    def _tail(self) -> str:
        try:
            self.stderr.seek(0, os.SEEK_END)
            size = self.stderr.tell()
            self.stderr.seek(max(0, size - MAX_STDERR))
            return self.stderr.read().decode(errors="replace").strip()
        except (OSError, ValueError):
            return ""

    def _ended(self, timed_out: bool) -> ConfinedTaskError:
        self.kill()
        why = _why_ended(self.proc.returncode, self.limits, timed_out)
        tail = self._tail().splitlines()[-3:]
        memory = any("MemoryError" in line for line in tail)
        return ConfinedTaskError(f"{why}" + (f"; stderr: {' | '.join(tail)}" if tail else ""),
                                 "MemoryError" if memory else None)

    def receive(self) -> dict[str, Any]:
        """The next answer, or the error that explains why none came."""
        deadline = time.monotonic() + self.limits.wall_s
        try:
            header = self._read_exact(4, deadline)
            answer = wire.decode_frame(self._read_exact(wire.frame_length(header, wire.MAX_FROM_JAIL), deadline))
        except TimeoutError:
            raise self._ended(True) from None
        except EOFError:
            raise self._ended(False) from None
        except wire.WireError:
            self.kill()
            raise
        if "violation" in answer:
            v = answer["violation"] if isinstance(answer["violation"], dict) else {}
            self.kill()
            raise GuardRefused(str(v.get("event", "?"))[:100], str(v.get("detail", ""))[:400])
        if "error" in answer:
            e = answer["error"] if isinstance(answer["error"], dict) else {}
            kind, message = str(e.get("type", "Error"))[:80], str(e.get("message", ""))[:1000]
            err = ConfinedTaskError(f"{kind}: {message}", kind)
            err.add_note(str(e.get("traceback", ""))[-1500:])
            raise err
        return answer

    def call(self, message: Mapping[str, Any]) -> dict[str, Any]:
        self.calls += 1
        self._send(message)
        return self.receive()

    def hello(self) -> TaskFacts:
        """The facts the loaded module states (waits for the answer to ``load``)."""
        if self.facts is None:
            self.facts = TaskFacts.from_dict(self.receive().get("facts"))
        return self.facts

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()  # bwrap dies; --die-with-parent and the PID namespace take the host with it
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:  # pragma: no cover - a process SIGKILL did not end
            pass

    def close(self) -> None:
        self.kill()
        for stream in (self.proc.stdin, self.proc.stdout, self.stderr):
            try:
                if stream is not None:
                    stream.close()
            except OSError:
                pass


def _close_all(processes: list[_Jailed]) -> None:
    for p in processes:
        p.close()
    processes.clear()


class ConfinedTask:
    """The task protocol, answered by a jailed process (see the module docstring).

    ``expected`` are the facts accepted at generation (from a manifest): the task's ``name``,
    ``tags`` and docstring come from them without starting a process, and a process that states
    different facts is refused.  Without them, the first access to a fact loads the module.
    ``spare=False`` starts no spare process (one process at a time, each episode waits for its own);
    ``guard=False`` leaves the audit hook out of the jail (only to measure what the jail stops alone).
    """

    name: str
    """The name the task states (a malformed one is kept as stated, for validation to report)."""
    tags: frozenset[str]

    def __init__(self, source: ModuleSource, limits: jail.Limits | None = None, *,
                 expected: TaskFacts | None = None, sample_goal: str | None = None, spare: bool = True,
                 guard: bool = True) -> None:
        self.source, self.limits, self.expected, self.use_spare = source, limits or jail.Limits(), expected, spare
        self.sample_goal, self.guard = sample_goal, guard
        """A goal text recorded at acceptance (for listings that must not start a process)."""
        self._lock = threading.RLock()
        self._current: _Jailed | None = None
        self._spare: _Jailed | None = None
        self._episode_used = False
        self._live: list[_Jailed] = []
        self.started = 0
        """How many jailed processes this task has started (one per episode, plus spares)."""
        self.refusals: list[dict[str, str]] = []
        """The events the runtime guard refused (``event``, ``detail``), in order."""
        self._finalizer = weakref.finalize(self, _close_all, self._live)
        if expected is not None:
            self._present(expected)

    # -- facts ------------------------------------------------------------------------------
    def _present(self, facts: TaskFacts) -> None:
        """Expose the facts as the protocol's attributes, mirroring the remote task's methods."""
        self.name = facts.name  # type: ignore[assignment]
        self.tags = frozenset(facts.tags) if facts.tags is not None else None  # type: ignore[assignment]
        self.__doc__ = facts.doc
        m = facts.methods
        if m.get(SCENE_METHOD):
            self.sample_scene: Callable[[np.random.Generator], Scene] = self._sample
        if m.get(DEPRECATED_SCENE_METHOD):  # aliased: the same bound method; else a different one
            setattr(self, DEPRECATED_SCENE_METHOD, self._sample if m.get("aliased") or not m.get(SCENE_METHOD)
                    else self._sample_legacy)
        if m.get("oracle_goals"):
            self.oracle_goals: Callable[[Scene], Sequence[OracleGoal]] = self._oracle_goals
        if m.get("evaluate"):
            self.evaluate: Callable[[Scene, SceneState], Verdict] = self._evaluate

    def __getattr__(self, attr: str) -> Any:
        """A protocol attribute of a task whose facts are not known yet: load the module first."""
        if attr in _FACT_ATTRIBUTES and self.__dict__.get("expected") is None and "_lock" in self.__dict__:
            self.load()
            if attr in self.__dict__:
                return self.__dict__[attr]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {attr!r}")

    def load(self) -> TaskFacts:
        """Start the first process, load the module and return its facts (checked against
        ``expected``).  Raises :class:`ConfinedTaskError` when the module fails to load."""
        with self._lock:
            return self._process().hello()

    @property
    def facts(self) -> TaskFacts:
        return self.expected if self.expected is not None else self.load()

    # -- processes --------------------------------------------------------------------------
    def _spawn(self) -> _Jailed:
        p = _Jailed(self.source, self.limits, self.guard)
        self._live.append(p)
        self.started += 1
        return p

    def _retire(self, p: _Jailed) -> None:
        p.close()
        if p in self._live:
            self._live.remove(p)

    def _process(self) -> _Jailed:
        if self._current is None:
            self._current = self._spare or self._spawn()
            self._spare = None
            try:
                facts = self._current.hello()
            except (ConfinementError, ConfinedTaskError) as e:
                if isinstance(e, GuardRefused):
                    self.refusals.append({"event": e.event, "detail": e.detail})
                self._retire(self._current)
                self._current = None
                raise
            if self.expected is not None and facts != self.expected:
                self._retire(self._current)
                self._current = None
                raise ConfinementError(
                    f"the generated task {self.source.module} states other facts than were accepted "
                    f"(name, tags, docstring or methods): {facts.to_dict()} != {self.expected.to_dict()}"[:600])
            if self.expected is None:
                self.expected = facts
                self._present(facts)
            if self.use_spare:
                self._spare = self._spawn()
        return self._current

    def _ask(self, message: Mapping[str, Any]) -> dict[str, Any]:
        p = self._process()
        try:
            return p.call(message)
        except GuardRefused as e:
            self.refusals.append({"event": e.event, "detail": e.detail})
            self._retire(p)
            self._current = None
            raise
        except (ConfinementError, ConfinedTaskError):
            if p.proc.poll() is not None or p.proc.returncode is not None:
                self._retire(p)
                self._current = None
            raise

    def new_episode(self) -> None:
        """Retire the current process: the next call goes to a fresh one."""
        with self._lock:
            if self._current is not None:
                self._retire(self._current)
                self._current = None
            self._episode_used = False

    def close(self) -> None:
        """End every process of this task (also done when it is garbage-collected)."""
        with self._lock:
            self._current = self._spare = None
            _close_all(self._live)

    # -- the protocol -----------------------------------------------------------------------
    def _sample(self, rng: np.random.Generator) -> Scene:
        from capmj.tasks.protocol import Resample

        with self._lock:
            if self._episode_used:
                self.new_episode()
            answer = self._ask({"op": "sample_scene", "rng": wire.rng_to_wire(rng)})
            rng.bit_generator.state = wire.rng_from_wire(answer.get("rng"))
            if answer.get("resample") is True:
                raise Resample
            return wire.scene_from_wire(answer.get("scene"))

    def _sample_legacy(self, rng: np.random.Generator) -> Scene:  # pragma: no cover - never called: refused first
        raise ConfinementError("a task defining two different scene methods is refused before it runs")

    def _oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        with self._lock:
            self._episode_used = True
            return wire.goals_from_wire(self._ask({"op": "oracle_goals", "scene": wire.scene_to_wire(scene)}).get("goals"))

    def _evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        with self._lock:
            self._episode_used = True
            answer = self._ask({"op": "evaluate", "scene": wire.scene_to_wire(scene), "state": wire.state_to_wire(state)})
            return wire.verdict_from_wire(answer.get("verdict"))

    def __repr__(self) -> str:
        return f"ConfinedTask({self.source.module!r}, sha256={self.source.sha256[:12]})"


__all__ = ["ConfinedTask", "HOST", "ModuleSource", "TaskFacts"]
