"""A generated task as capmj sees it: a :class:`ConfinedTask` that forwards each protocol call to a
jailed process and believes only validated data.

capmj never imports generated code.  :class:`ConfinedTask` holds the module's exact text and
final module name (:class:`ModuleSource`) and implements the task protocol by asking a task
process (:mod:`capmj.confine.host`) in its jail: ``sample_scene`` sends the caller's generator state and sets the
advanced state it gets back (a seed still maps to exactly one scene, as in-process), and the
scene, goals and verdict come back through :mod:`capmj.confine.wire`.  The physics, the oracle,
every check and every record stay in capmj's process; the jail only answers questions.

**A fresh process per episode.**  Once a task process has answered ``oracle_goals`` or
``evaluate``, the next ``sample_scene`` — the start of the next episode — goes to a new one, so
state a task keeps between calls (a call counter, a patched module, a file in its tmpfs) never
outlives one episode.  The jail's fork server (:mod:`capmj.confine.forkserver`) makes that cheap:
a ``fork`` of an interpreter that has the task API imported, not a new interpreter.  A jail that
times out or dies is replaced by a new one.

**Facts.**  A loaded task states its name, tags, docstring and protocol methods.  For an
installed package the manifest holds the facts accepted at generation (``expected``); a process
that states other facts is refused with :class:`~capmj.errors.ConfinementError`.  Reading the
facts from the manifest starts no process, so listing tasks never runs generated code.
"""

from __future__ import annotations

import os
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
from capmj.confine.manifest import sha256_text
from capmj.errors import ConfinedTaskError, ConfinementError, GuardRefused
from capmj.sim.state import SceneState
from capmj.tasks.protocol import OracleGoal, Scene, Verdict
from capmj.tasks.scene_method import DEPRECATED_SCENE_METHOD, SCENE_METHOD

FORKSERVER = ("-I", "-B", "-m", "capmj.confine.forkserver")
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
        return sha256_text(self.text)


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


def _why_ended(limits: jail.Limits, *, signum: int | None = None, exit_code: int | None = None,
               timed_out: bool = False) -> str:
    """Why a task process (or the whole jail) ended, naming the limit that ended it."""
    if timed_out:
        return f"killed: wall-clock limit of {limits.wall_s:g} s exceeded"
    if signum is not None:
        if signum in (signal.SIGXCPU, signal.SIGKILL):
            return f"killed: CPU-time limit of {limits.cpu_s} s exceeded ({signal.Signals(signum).name})"
        if signum == signal.SIGXFSZ:
            return f"killed: file-size limit of {limits.tmpfs_mb} MiB exceeded (SIGXFSZ)"
        return f"killed by signal {signal.Signals(signum).name}" if signum in signal.valid_signals() else f"signal {signum}"
    if exit_code == VIOLATION_EXIT:
        return "ended by the runtime guard"
    return f"the task process exited with code {exit_code}"


class _Jail:
    """One jail: bwrap around the fork server, its frame channel, and the task process it serves."""

    def __init__(self, source: ModuleSource, limits: jail.Limits, guard: bool) -> None:
        self.limits = limits
        self.stderr: IO[bytes] = tempfile.TemporaryFile(prefix="capmj-jail-")  # noqa: SIM115 - closed in close()
        self.proc = jail.start([sys.executable, *FORKSERVER], limits, self.stderr)
        self.child_alive = False
        self._send({"op": "load", "module": source.module, "text": source.text, "guard": guard})

    def _send(self, message: Mapping[str, Any]) -> None:
        assert self.proc.stdin is not None
        try:
            wire.write_frame(self.proc.stdin, message)
        except (BrokenPipeError, OSError):
            pass  # the jail is gone; the read that follows says why

    def _read_exact(self, n: int, deadline: float) -> bytes:
        assert self.proc.stdout is not None
        return wire.read_exact(self.proc.stdout.fileno(), n, deadline)

    def _tail(self) -> list[str]:
        try:
            self.stderr.seek(0, os.SEEK_END)
            size = self.stderr.tell()
            self.stderr.seek(max(0, size - MAX_STDERR))
            return self.stderr.read().decode(errors="replace").strip().splitlines()[-3:]
        except (OSError, ValueError):
            return []

    def _ended(self, why: str) -> ConfinedTaskError:
        tail = self._tail()
        memory = any("MemoryError" in line for line in tail)
        return ConfinedTaskError(why + (f"; stderr: {' | '.join(tail)}" if tail else ""), "MemoryError" if memory else None)

    def receive(self) -> dict[str, Any]:
        """The next answer, or the error that explains why none came (the jail is killed on a
        timeout, a closed channel or a malformed frame)."""
        deadline = time.monotonic() + self.limits.wall_s
        try:
            header = self._read_exact(4, deadline)
            answer = wire.decode_frame(self._read_exact(wire.frame_length(header, wire.MAX_FROM_JAIL), deadline))
        except TimeoutError:
            self.kill()
            raise self._ended(_why_ended(self.limits, timed_out=True)) from None
        except EOFError:
            self.kill()
            code = self.proc.returncode
            bwrap = [line for line in self._tail() if line.startswith("bwrap:")]
            if bwrap:  # the jail itself could not be made: not the task's fault
                raise ConfinementError(jail.refused(bwrap[-1])) from None
            raise self._ended(_why_ended(self.limits, signum=code - 128 if code and code > 128 else None,
                                         exit_code=code)) from None
        except wire.WireError:
            self.kill()
            raise
        self.child_alive = True
        if "ended" in answer:  # the task process ended without answering; the fork server says how
            self.child_alive = False
            e = answer["ended"] if isinstance(answer["ended"], dict) else {}
            if "wire" in e:
                raise wire.WireError(str(e["wire"])[:300])
            sig, code = e.get("signal"), e.get("exit")
            raise self._ended(_why_ended(self.limits, signum=sig if isinstance(sig, int) else None,
                                         exit_code=code if isinstance(code, int) else None))
        if "violation" in answer:
            self.child_alive = False  # the guard ends the task process
            v = answer["violation"] if isinstance(answer["violation"], dict) else {}
            raise GuardRefused(str(v.get("event", "?"))[:100], str(v.get("detail", ""))[:400])
        if "error" in answer:
            e = answer["error"] if isinstance(answer["error"], dict) else {}
            kind, message = str(e.get("type", "Error"))[:80], str(e.get("message", ""))[:1000]
            err = ConfinedTaskError(f"{kind}: {message}", kind)
            err.add_note(str(e.get("traceback", ""))[-1500:])
            raise err
        return answer

    def call(self, message: Mapping[str, Any]) -> dict[str, Any]:
        self._send(message)
        return self.receive()

    def facts(self) -> TaskFacts:
        """The facts the freshly loaded module states (the answer to ``load`` or ``fresh``)."""
        return TaskFacts.from_dict(self.receive().get("facts"))

    def fresh(self) -> TaskFacts:
        """A new task process in this jail, the tmpfs emptied, the module loaded again."""
        self._send({"op": "fresh"})
        return self.facts()

    @property
    def alive(self) -> bool:
        return self.proc.poll() is None

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()  # bwrap dies; --die-with-parent and the PID namespace take the rest with it
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


class _PerThread(threading.local):
    """One jail per thread that uses the task: episodes that run at once in threads
    (``--concurrency``) each get their own task processes, and a fresh one per episode."""

    jail: _Jail | None = None
    episode_used = False


def _close_all(jails: list[_Jail]) -> None:
    for j in jails:
        j.close()
    jails.clear()


class ConfinedTask:
    """The task protocol, answered by a jailed process (see the module docstring).

    ``expected`` are the facts accepted at generation (from a manifest): the task's ``name``,
    ``tags`` and docstring come from them without starting a process, and a process that states
    different facts is refused.  Without them, the first access to a fact loads the module.
    ``guard=False`` leaves the audit hook out of the jail (only to measure what the jail stops alone).
    """

    name: str
    """The name the task states (a malformed one is kept as stated, for validation to report)."""
    tags: frozenset[str]

    def __init__(self, source: ModuleSource, limits: jail.Limits | None = None, *,
                 expected: TaskFacts | None = None, sample_goal: str | None = None, guard: bool = True) -> None:
        self.source, self.limits, self.expected = source, limits or jail.Limits(), expected
        self.sample_goal = sample_goal
        """A goal text recorded at acceptance (for listings that must not start a process)."""
        self.guard = guard
        self._lock = threading.RLock()
        self._local = _PerThread()
        self._live: list[_Jail] = []
        self.started = 0
        """How many task processes this task has started (one per episode, and after a failure)."""
        self.jails = 0
        """How many jails (fork servers) it has started (one, unless a jail had to be killed)."""
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
        """Start the jail, load the module and return its facts (checked against ``expected``).
        Raises :class:`ConfinedTaskError` when the module fails to load."""
        with self._lock:
            self._task_process()
            assert self.expected is not None
            return self.expected

    # -- processes --------------------------------------------------------------------------
    def _kill_jail(self) -> None:
        j = self._local.jail
        if j is not None:
            j.close()
            with self._lock:
                if j in self._live:
                    self._live.remove(j)
            self._local.jail = None

    def _checked(self, load: Callable[[], TaskFacts]) -> None:
        """Run ``load`` (a first load or a fresh task process) and hold its facts to ``expected``."""
        with self._lock:
            self.started += 1
        try:
            facts = load()
        except GuardRefused as e:
            with self._lock:
                self.refusals.append({"event": e.event, "detail": e.detail})
            raise
        with self._lock:
            if self.expected is None:
                self.expected = facts
                self._present(facts)
            same = facts == self.expected
        if not same:
            self._kill_jail()
            raise ConfinementError(
                f"the generated task {self.source.module} states other facts than were accepted "
                f"(name, tags, docstring or methods): {facts.to_dict()} != {self.expected.to_dict()}"[:600])

    def _task_process(self) -> _Jail:
        """The jail whose task process serves this episode (a jail, or a task process, as needed)."""
        local = self._local
        if local.jail is not None and not local.jail.alive:
            self._kill_jail()
        if local.jail is None:
            local.jail = _Jail(self.source, self.limits, self.guard)
            with self._lock:
                self._live.append(local.jail)
                self.jails += 1
            self._checked(local.jail.facts)
        elif not local.jail.child_alive:
            self._checked(local.jail.fresh)
        return local.jail

    def _ask(self, message: Mapping[str, Any]) -> dict[str, Any]:
        j = self._task_process()
        try:
            return j.call(message)
        except GuardRefused as e:
            with self._lock:
                self.refusals.append({"event": e.event, "detail": e.detail})
            raise

    def new_episode(self) -> None:
        """The next call goes to a fresh task process (the current one is killed first)."""
        if self._local.jail is not None:
            self._local.jail.child_alive = False
        self._local.episode_used = False

    def close(self) -> None:
        """End the jail of this task (also done when it is garbage-collected)."""
        with self._lock:
            _close_all(self._live)
        self._local = _PerThread()

    # -- the protocol -----------------------------------------------------------------------
    def _sample(self, rng: np.random.Generator) -> Scene:
        from capmj.tasks.protocol import Resample

        if self._local.episode_used:
            self.new_episode()
        answer = self._ask({"op": "sample_scene", "rng": wire.rng_to_wire(rng)})
        rng.bit_generator.state = wire.rng_from_wire(answer.get("rng"))
        if answer.get("resample") is True:
            raise Resample
        return wire.scene_from_wire(answer.get("scene"))

    def _sample_legacy(self, rng: np.random.Generator) -> Scene:  # pragma: no cover - never called: refused first
        raise ConfinementError("a task defining two different scene methods is refused before it runs")

    def _oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        self._local.episode_used = True
        return wire.goals_from_wire(self._ask({"op": "oracle_goals", "scene": wire.scene_to_wire(scene)}).get("goals"))

    def _evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        self._local.episode_used = True
        answer = self._ask({"op": "evaluate", "scene": wire.scene_to_wire(scene), "state": wire.state_to_wire(state)})
        return wire.verdict_from_wire(answer.get("verdict"))

    def __repr__(self) -> str:
        return f"ConfinedTask({self.source.module!r}, sha256={self.source.sha256[:12]})"


__all__ = ["FORKSERVER", "ConfinedTask", "ModuleSource", "TaskFacts"]
