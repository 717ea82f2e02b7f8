"""The jailed fork server: ``python -m capmj.confine.forkserver``, one per jail.

It runs only trusted code.  It imports the task API once (numpy, the protocol, spawn, predicates),
makes itself non-dumpable (a task process, same uid, cannot read or write its memory or
descriptors through ``/proc``), and then serves the parent on its stdin/stdout:

- ``load`` (the module's text, its name, whether to guard): remembered, and sent to a new task
  process forked for it;
- ``fresh``: the current task process is killed, the tmpfs is emptied, and a new task process
  loads the remembered module — a fresh process per episode for the cost of one ``exec`` of the
  module, not an interpreter start: the next task process is forked as soon as an answer is sent
  (it holds no generated code until its load) and the module is compiled once, here;
- anything else is relayed to the current task process, frame for frame.

A task process (:mod:`capmj.confine.host`) is forked *before* any generated code exists in it,
closes every descriptor but its own pipes and stderr, installs the seccomp filter and only then
loads the module.  The fork server never parses what a task process sends: it checks the frame's
announced length against :data:`~capmj.confine.wire.MAX_FROM_JAIL` and copies the bytes.  When a
task process ends without answering, the fork server answers ``{"ended": {...}}`` with its exit
code or signal, so the parent can name the limit that ended it.
"""

from __future__ import annotations

import ctypes
import json
import os
import signal
import stat
from typing import Any

from capmj.confine import wire
from capmj.confine.jail import TMP

_PR_SET_DUMPABLE = 4


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


def read_raw(fd: int, limit: int) -> bytes:
    """One frame's payload from ``fd``, its length checked against ``limit`` (EOF: ``EOFError``)."""
    return wire.read_exact(fd, wire.frame_length(wire.read_exact(fd, 4), limit))


def write_raw(fd: int, payload: bytes) -> None:
    _write_all(fd, len(payload).to_bytes(4, "big") + payload)


def _frame(message: dict[str, Any]) -> bytes:
    return json.dumps(message, allow_nan=False, separators=(",", ":")).encode()


def _wipe(root: str) -> None:
    """Empty ``root`` (the jail's tmpfs), whatever modes a task process left on what it made there.

    Read-only binds inside it (an interpreter or virtualenv under ``/tmp``) are other file systems
    and stay; the tmpfs directories leading to them stay too, emptied of anything else."""
    dev = os.lstat(root).st_dev
    for name in os.listdir(root):
        path = os.path.join(root, name)
        try:
            st = os.lstat(path)
        except OSError:
            continue
        if st.st_dev != dev:
            continue
        if stat.S_ISDIR(st.st_mode):
            if st.st_mode & 0o700 != 0o700:
                os.chmod(path, st.st_mode | 0o700)
            _wipe(path)
            try:
                os.rmdir(path)
            except OSError:  # it leads to a bind mount
                pass
        else:
            os.unlink(path)


class TaskProcess:
    """A forked task process and its two pipes."""

    def __init__(self) -> None:
        from_parent, to_child = os.pipe()
        from_child, to_parent = os.pipe()
        self.pid = os.fork()
        if self.pid == 0:  # the task process: never returns into the fork server's loop
            code = 1
            try:
                _close_others({from_parent, to_parent})
                from capmj.confine import host, seccomp

                seccomp.install()
                host.serve(os.fdopen(from_parent, "rb", buffering=0), os.fdopen(to_parent, "wb"))
                code = 0
            finally:
                os._exit(code)
        os.close(from_parent)
        os.close(to_parent)
        self.to_child, self.from_child = to_child, from_child
        self.ended: dict[str, Any] | None = None

    def ask(self, payload: bytes) -> bytes:
        """Send one frame, return the answer's payload (or the ``ended`` report when none came)."""
        try:
            write_raw(self.to_child, payload)
            return read_raw(self.from_child, wire.MAX_FROM_JAIL)
        except (EOFError, BrokenPipeError):
            return _frame({"ended": self.reap()})
        except wire.WireError as e:  # an announced length over the limit: the process is done
            self.kill()
            return _frame({"ended": {**self.reap(), "wire": str(e)}})

    def reap(self) -> dict[str, Any]:
        if self.ended is None:
            try:
                _, status = os.waitpid(self.pid, 0)
            except ChildProcessError:
                status = None
            self.ended = ({"exit": None} if status is None else {"signal": os.WTERMSIG(status)}
                          if os.WIFSIGNALED(status) else {"exit": os.WEXITSTATUS(status)})
        return self.ended

    def kill(self) -> None:
        if self.ended is None:  # never a pid already reaped (it may be another process's by now)
            try:
                os.kill(self.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass

    def close(self) -> None:
        self.kill()
        self.reap()
        for fd in (self.to_child, self.from_child):
            try:
                os.close(fd)
            except OSError:
                pass


def _close_others(keep: set[int]) -> None:
    """Close every descriptor above 2 but ``keep`` (a task process inherits nothing else)."""
    for name in os.listdir("/proc/self/fd"):
        fd = int(name)
        if fd > 2 and fd not in keep:
            try:
                os.close(fd)
            except OSError:
                pass


def main() -> int:
    # trusted start-up: everything the task API needs, before any task process exists (numpy loads
    # numpy.random on first use: done here once, not in every task process)
    import numpy
    import numpy.linalg  # noqa: F401
    import numpy.random

    numpy.random.Generator(numpy.random.PCG64(0)).random()

    import capmj.confine.host  # noqa: F401
    import capmj.confine.seccomp  # noqa: F401
    import capmj.tasks.predicates  # noqa: F401
    import capmj.tasks.protocol  # noqa: F401
    import capmj.tasks.scene_method  # noqa: F401
    import capmj.tasks.spawn  # noqa: F401
    from capmj.confine import guard  # noqa: F401 - imported here, installed in the task process

    inp, out = os.dup(0), os.dup(1)
    null = os.open(os.devnull, os.O_RDWR)
    os.dup2(null, 0)
    os.dup2(2, 1)  # a task's print goes where stderr goes
    os.close(null)
    ctypes.CDLL(None).prctl(_PR_SET_DUMPABLE, 0, 0, 0, 0)
    module: bytes | None = None
    child: TaskProcess | None = None
    ready: TaskProcess | None = None  # forked ahead, no generated code in it yet: waits for its load
    while True:
        try:
            payload = read_raw(inp, wire.MAX_TO_JAIL)
        except (EOFError, wire.WireError):
            return 0  # the parent closed the channel
        msg = json.loads(payload)  # the parent's own frame
        op = msg.get("op")
        if op in ("load", "fresh"):
            if child is not None:
                child.close()
                _wipe(TMP)  # before the next task process runs any generated code
            if op == "load":
                module = payload
                _precompile(str(msg.get("module")), str(msg.get("text")))
                if ready is not None:  # forked before this code was compiled
                    ready.close()
                    ready = None
            if module is None:
                write_raw(out, _frame({"error": {"type": "WireError", "message": "fresh before load"}}))
                continue
            child, ready = ready or TaskProcess(), None
            write_raw(out, child.ask(module))
            ready = TaskProcess()  # while the parent works with the answer
            continue
        if child is None:
            write_raw(out, _frame({"error": {"type": "WireError", "message": f"{op!r} before load"}}))
            continue
        write_raw(out, child.ask(payload))


def _precompile(name: str, text: str) -> None:
    """Compile the module once here (compiling runs none of it), so every task process forked
    from now on inherits the code object instead of compiling it again; a module the compiler
    refuses is left to the task process, which reports the error as its answer."""
    from capmj.confine import host

    try:
        host.PRECOMPILED[name] = (text, compile(text, host.CANDIDATE_FILE, "exec"))
    except (SyntaxError, ValueError, RecursionError, MemoryError, OverflowError):
        host.PRECOMPILED.pop(name, None)


if __name__ == "__main__":
    raise SystemExit(main())
