"""An early rejection inside the jail: a PEP 578 audit hook that names what the static check missed.

It lives in the same interpreter as the generated code, so it is *not* the boundary (code that
reaches the interpreter's internals can switch it off; the jail, :mod:`capmj.confine.jail`, and
the seccomp filter hold regardless).  Its job is the explanation: a refused event becomes the
candidate's rejection reason, naming the door.  Installed by the jailed host
(:mod:`capmj.confine.host`) after its own trusted imports and before it loads a candidate, it
watches every audit event of the process for the rest of its life:

- **process creation and signals**: ``os.system``, ``os.exec*``, ``os.spawn*``,
  ``os.posix_spawn``, ``os.fork``/``forkpty``, ``subprocess.Popen``, ``os.kill``;
- **writing to the file system**: ``open`` for writing, appending or creating (``open()``,
  ``io.open``, ``os.open`` alike), and removing, renaming, linking, ``chmod``/``chown``,
  ``mkdir``, ``shutil`` and ``tempfile`` operations, environment changes;
- **the network**: every ``socket.*`` event (creation, connect, bind, name lookups) and the
  clients built on it;
- **native code**: every ``ctypes.*`` event (``dlopen``, ``dlsym``, calls, raw memory), raised
  limits (``resource.setrlimit``/``prlimit``);
- **imports outside the allow-list** made by the candidate itself (the ``import`` event and,
  for ``importlib.import_module``, a finder at the front of ``sys.meta_path``).  Imports that
  trusted code makes on the candidate's behalf are allowed; their effects are watched like any.

A refusal is final: the hook reports the event to the parent and ends the process at once (``os._exit``), so a candidate cannot catch the exception and carry on.  What
this layer does not stop is written down in ``docs/security.md``.
"""

from __future__ import annotations

import os
import sys
from importlib.abc import MetaPathFinder
from types import FrameType
from typing import Any, Callable, Sequence

from capmj.confine.allowlist import IMPORTABLE

VIOLATION_EXIT = 86
"""Exit code of a task process the guard ended (the parent also reads the reported event)."""

REFUSED_EVENTS = (
    "os.system", "os.exec", "os.spawn", "os.posix_spawn", "os.fork", "os.forkpty", "subprocess.", "pty.",
    "os.kill", "os.killpg", "signal.pthread_kill", "os.remove", "os.rmdir", "os.rename", "os.mkdir",
    "os.symlink", "os.link", "os.chmod", "os.chown", "os.chflags", "os.lchflags", "os.truncate", "os.utime",
    "os.setxattr", "os.removexattr", "os.putenv", "os.unsetenv", "os.chdir", "os.startfile", "shutil.",
    "tempfile.", "sqlite3.connect", "socket.", "urllib.", "http.client.", "ftplib.", "smtplib.", "poplib.",
    "imaplib.", "nntplib.", "telnetlib.", "webbrowser.", "ctypes.", "resource.setrlimit", "resource.prlimit",
    "sys.addaudithook", "sys.settrace", "sys.setprofile",
)
"""Audit events (exact names or prefixes ending in '.') the guard refuses from anyone."""

_WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_APPEND | os.O_CREAT | os.O_TRUNC


def opens_for_writing(args: Sequence[Any]) -> bool:
    """Whether an ``open`` event's ``(path, mode, flags)`` asks for more than reading."""
    mode, flags = (list(args) + [None, None])[1:3]
    if isinstance(mode, str) and any(c in mode for c in "wax+"):
        return True
    return isinstance(flags, int) and bool(flags & _WRITE_FLAGS)


def _module_allowed(name: str) -> bool:
    return name in IMPORTABLE or any(name.startswith(m + ".") for m in IMPORTABLE if m.startswith("capmj."))


class Guard:
    """The hook's state: the candidate's file, where to report, the check now running."""

    def __init__(self, candidate: str, report: Callable[[dict[str, Any]], None]) -> None:
        self.candidate = candidate
        self.report = report
        self.check = ""
        self._busy = False

    # -- who is importing --------------------------------------------------------------------
    def _importer_is_candidate(self) -> bool:
        """The nearest frame outside the import machinery belongs to the candidate's file (or to
        code compiled at run time, whose file is no real module: ``<string>`` and the like;
        frozen standard-library modules, ``<frozen ...>``, are trusted)."""
        f: FrameType | None = sys._getframe(2)
        while f is not None:
            name = f.f_code.co_filename
            if not (name.startswith("<frozen") or "/importlib/" in name or name == __file__):
                return name == self.candidate or name.startswith("<")
            f = f.f_back
        return False

    # -- refusing ----------------------------------------------------------------------------
    def refuse(self, event: str, args: Sequence[Any]) -> None:
        """Record the event and end the process; never returns."""
        detail = f"{event}{tuple(args)!r}"[:400]
        try:
            self.report({"violation": {"event": event, "detail": detail, "check": self.check}})
        finally:
            os._exit(VIOLATION_EXIT)

    def __call__(self, event: str, args: tuple[Any, ...]) -> None:
        if self._busy:
            return
        refused = (event.startswith(REFUSED_EVENTS) or (event == "open" and opens_for_writing(args))
                   or (event == "import" and not _module_allowed(str(args[0])) and self._importer_is_candidate()))
        if refused:
            self._busy = True
            self.refuse(event, args)

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> None:
        """The ``sys.meta_path`` side: ``importlib.import_module`` raises no ``import`` event."""
        if not self._busy and not _module_allowed(fullname) and self._importer_is_candidate():
            self._busy = True
            self.refuse("import", (fullname, "importlib"))
        return None


class _Finder(MetaPathFinder):
    def __init__(self, guard: Guard) -> None:
        self.guard = guard

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> None:  # type: ignore[override]
        return self.guard.find_spec(fullname, path, target)


def install(candidate: str, report: Callable[[dict[str, Any]], None]) -> Guard:
    """Install the guard for the rest of the process (an audit hook cannot be removed).

    ``candidate`` is the file name the generated code was compiled with; ``report`` is called with
    ``{"violation": {...}}`` before the process ends.
    """
    guard = Guard(candidate, report)
    sys.addaudithook(guard)
    sys.meta_path.insert(0, _Finder(guard))
    return guard


__all__ = ["Guard", "REFUSED_EVENTS", "VIOLATION_EXIT", "install", "opens_for_writing"]
