"""The OS boundary for LLM-written task code: a ``bwrap`` (bubblewrap) jail around one process.

Why bubblewrap: it is the small, setuid-free sandbox builder Flatpak relies on, packaged by every
distribution, and it does the whole job in one audited C program: new user, PID, mount, network,
IPC, UTS and cgroup namespaces; a fresh root built from read-only binds, with a private size-bounded
tmpfs as the only writable place; no capabilities; an unprivileged uid; death with its parent; a
clean environment.  Doing the same by hand from Python (``unshare``/``setpriv`` and mount calls in
a ``preexec_fn``) would re-implement bwrap's pivot-root and mount sequencing, the part that is easy
to get subtly wrong.  What bwrap does not do is filter system calls by argument without a compiled
BPF program, so the jailed process installs its own seccomp filter before it loads any generated
code (:mod:`capmj.confine.seccomp`), and rlimits are set on the jail before ``exec``.

The root the jail sees holds only what the Python interpreter and capmj need to *read*: the
interpreter's prefixes, the site directories on ``sys.path``, capmj's package root, ``/usr``
(with the merged-usr links) and the loader cache.  No home directory, no run folders, no sockets, no ``/proc`` of the host (the
jail's own ``/proc`` shows only its PID namespace).

:func:`jail_command` is pure (an argv); :func:`start` runs it under the limits.  :func:`problem`
says why a machine cannot jail (no ``bwrap``, namespaces refused), once, with the fix; capmj then
refuses to run generated code at all: there is no unconfined fallback.
"""

from __future__ import annotations

import functools
import os
import resource
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Callable, Sequence

from capmj.errors import ConfigError, ConfinementError

BWRAP = "bwrap"
NOBODY = 65534
"""The uid and gid of the jailed process (``nobody``): no file of the host belongs to it."""
TMP = "/tmp"
"""The jail's only writable directory (a private tmpfs)."""
CLEAN_ENV: dict[str, str] = {
    "HOME": TMP, "PATH": "/usr/bin:/bin", "LANG": "C.UTF-8", "PYTHONHASHSEED": "0", "PYTHONDONTWRITEBYTECODE": "1",
    "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
}
"""The jail's whole environment (``--clearenv`` first): no key, token or path of the host's."""
_SYSTEM_LINKS = ("/bin", "/lib", "/lib64", "/lib32", "/libx32", "/sbin")


@dataclass(frozen=True)
class Limits:
    """Resources of one jailed process: CPU seconds (``RLIMIT_CPU``, then SIGXCPU), address
    space in MiB (``RLIMIT_AS``: a runaway allocation gets a ``MemoryError``), wall seconds one
    call may take before the process is killed, the size of its tmpfs and of any file it
    writes (``RLIMIT_FSIZE``) in MiB, and open files (``RLIMIT_NOFILE``)."""

    cpu_s: int = 300
    memory_mb: int = 4096
    wall_s: float = 600.0
    tmpfs_mb: int = 16
    open_files: int = 64

    def __post_init__(self) -> None:
        if self.cpu_s < 1 or self.memory_mb < 256 or self.wall_s <= 0 or self.tmpfs_mb < 1 or self.open_files < 16:
            raise ConfigError(f"limits need cpu_s >= 1, memory_mb >= 256, wall_s > 0, tmpfs_mb >= 1, "
                              f"open_files >= 16; got {self}")


SITE_DIRS = ("site-packages", "dist-packages")


def _readable_roots() -> list[str]:
    """Host paths the jail binds read-only: the interpreter's prefixes, the site directories on
    ``sys.path``, capmj's own package root and ``/usr``.  Other ``sys.path`` entries (a script's
    folder, ``PYTHONPATH``, the working directory) are left out: they may hold a project's files."""
    paths = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix, "/usr"}
    paths.update(p for p in sys.path if os.path.isabs(p) and os.path.basename(os.path.normpath(p)) in SITE_DIRS)
    import capmj  # the package itself: an editable install maps it from outside sys.path

    paths.add(str(Path(capmj.__file__).resolve().parents[1]))
    existing = sorted({str(Path(p)) for p in paths if os.path.isdir(p)})
    # a path inside another bound path needs no bind of its own
    return [p for p in existing if not any(p != q and p.startswith(q.rstrip("/") + "/") for q in existing)]


def jail_command(argv: Sequence[str], limits: Limits | None = None) -> list[str]:
    """The ``bwrap`` command line that runs ``argv`` jailed (see the module docstring)."""
    limits = limits or Limits()
    cmd = [shutil.which(BWRAP) or BWRAP, "--unshare-all", "--unshare-user", "--disable-userns", "--die-with-parent",
           "--new-session", "--cap-drop", "ALL", "--uid", str(NOBODY), "--gid", str(NOBODY), "--clearenv",
           "--proc", "/proc", "--dev", "/dev", "--size", str(limits.tmpfs_mb << 20), "--tmpfs", TMP]
    # the binds come after the tmpfs: an interpreter or venv under /tmp stays visible (read-only)
    for link in _SYSTEM_LINKS:
        if os.path.islink(link):
            cmd += ["--symlink", os.readlink(link), link]
        elif os.path.isdir(link):
            cmd += ["--ro-bind", link, link]
    for path in _readable_roots():
        cmd += ["--ro-bind", path, path]
    if os.path.exists("/etc/ld.so.cache"):
        cmd += ["--ro-bind", "/etc/ld.so.cache", "/etc/ld.so.cache"]
    cmd += ["--remount-ro", "/", "--chdir", TMP]
    for key, value in CLEAN_ENV.items():
        cmd += ["--setenv", key, value]
    return [*cmd, "--", *argv]


def _rlimits(limits: Limits) -> Callable[[], None]:
    def apply() -> None:  # in the child between fork and exec of bwrap; the jail inherits them
        resource.setrlimit(resource.RLIMIT_CPU, (limits.cpu_s, limits.cpu_s + 2))
        mem = limits.memory_mb << 20
        resource.setrlimit(resource.RLIMIT_AS, (mem, mem))
        size = limits.tmpfs_mb << 20
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
        resource.setrlimit(resource.RLIMIT_NOFILE, (limits.open_files, limits.open_files))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    return apply


NOT_INSTALLED = ("bubblewrap is not installed; LLM-written task code runs only inside it "
                 "(Debian/Ubuntu: sudo apt-get install bubblewrap)")


def refused(bwrap_message: str) -> str:
    """The explanation of a jail bwrap could not create (``bwrap_message``: its own last line)."""
    return (f"bubblewrap cannot create the jail here ({bwrap_message}); it needs user namespaces "
            "(sysctl kernel.unprivileged_userns_clone=1, or a container that allows them)")


@functools.cache
def problem() -> str | None:
    """Why this machine cannot jail a process (``None``: it can).  Tried once per process, by
    starting one jailed interpreter."""
    if shutil.which(BWRAP) is None:
        return NOT_INSTALLED
    try:
        probe = subprocess.run(jail_command([sys.executable, "-I", "-c", "pass"]), capture_output=True, timeout=60,
                               stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError) as e:
        return f"bubblewrap could not be started: {type(e).__name__}: {e}"
    if probe.returncode != 0:
        err = probe.stderr.decode(errors="replace").strip().splitlines()[-1:] or ["no message"]
        return refused(err[0])
    return None


def require() -> None:
    """Raise :class:`ConfinementError` naming the fix when this machine cannot jail."""
    why = problem()
    if why is not None:
        raise ConfinementError(why)


def start(argv: Sequence[str], limits: Limits, stderr: IO[bytes]) -> subprocess.Popen[bytes]:
    """Start ``argv`` jailed under ``limits``, speaking on its stdin/stdout pipes.

    Only whether ``bwrap`` is installed is checked first (:class:`ConfinementError` if not); a jail
    bwrap then cannot create ends at once with bwrap's own message on ``stderr`` (:func:`refused`
    words it), so a run pays for no probe."""
    if shutil.which(BWRAP) is None:
        raise ConfinementError(NOT_INSTALLED)
    cmd = jail_command(argv, limits)
    return _launcher().submit(subprocess.Popen, cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=stderr,
                              preexec_fn=_rlimits(limits), close_fds=True, env={}).result()


@functools.cache
def _launcher() -> ThreadPoolExecutor:
    """The one thread that starts every jail.  ``--die-with-parent`` follows the *thread* that
    started bwrap (``PR_SET_PDEATHSIG``), so a jail started from an episode thread would die when
    a thread pool retires that thread; this thread lives as long as the process."""
    return ThreadPoolExecutor(max_workers=1, thread_name_prefix="capmj-jail-launcher")


__all__ = ["CLEAN_ENV", "Limits", "NOBODY", "NOT_INSTALLED", "TMP", "jail_command", "problem", "refused", "require", "start"]
