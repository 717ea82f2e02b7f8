"""A seccomp filter the jailed process installs on itself before it loads generated code.

The jail (:mod:`capmj.confine.jail`) already gives the process no network, no writable file
outside its tmpfs and no view of other processes.  The filter takes away what it could still do
inside: start a program (``execve``, ``execveat``), start a process (``fork``, ``vfork``, a
``clone`` without ``CLONE_THREAD``, ``clone3``), trace one (``ptrace``) or open a socket.  Threads
stay possible (``clone`` with ``CLONE_THREAD``; ``clone3`` answers ``ENOSYS`` and the C library
falls back to ``clone``).  Refused calls fail with ``EPERM`` instead of killing the process, so the
refusal surfaces as a Python ``PermissionError`` with a traceback the parent records.

The program is assembled here (a dozen classic-BPF instructions per architecture) instead of
taking a dependency on libseccomp: it is small, and it is checked by the tests (a fork, an exec and
a socket refused, a thread allowed).  A filter cannot be removed once installed, and it is
inherited by every thread.  Unknown architectures raise :class:`NotImplementedError` — the caller
refuses to run generated code rather than run it unfiltered.
"""

from __future__ import annotations

import ctypes
import errno
import platform
import struct

_LD_W_ABS, _JEQ_K, _JSET_K, _RET_K = 0x20, 0x15, 0x45, 0x06
_RET_ALLOW, _RET_ERRNO, _RET_KILL = 0x7FFF0000, 0x00050000, 0x80000000
_PR_SET_NO_NEW_PRIVS, _PR_SET_SECCOMP, _SECCOMP_MODE_FILTER = 38, 22, 2
_CLONE_THREAD = 0x00010000
_X32_BIT = 0x40000000

ARCHES: dict[str, tuple[int, dict[str, int]]] = {
    "x86_64": (0xC000003E, {"clone": 56, "fork": 57, "vfork": 58, "execve": 59, "execveat": 322, "clone3": 435,
                            "ptrace": 101, "socket": 41, "socketpair": 53}),
    "aarch64": (0xC00000B7, {"clone": 220, "execve": 221, "execveat": 281, "clone3": 435, "ptrace": 117,
                             "socket": 198, "socketpair": 199}),
}
"""Per machine: the audit arch of ``seccomp_data.arch`` and the numbers of the refused calls."""

REFUSED = ("fork", "vfork", "execve", "execveat", "ptrace", "socket", "socketpair")
"""Refused outright (``EPERM``); ``clone`` only without ``CLONE_THREAD``, ``clone3`` with ``ENOSYS``."""


def _ins(code: int, k: int, jt: int = 0, jf: int = 0) -> bytes:
    return struct.pack("HBBI", code, jt, jf, k)


def program(machine: str | None = None) -> bytes:
    """The filter for ``machine`` (default: this one) as raw ``sock_filter`` instructions."""
    machine = machine or platform.machine()
    if machine not in ARCHES:
        raise NotImplementedError(f"no seccomp filter for machine {machine!r}; known: {', '.join(ARCHES)}")
    arch, nr = ARCHES[machine]
    eperm, enosys = _RET_ERRNO | errno.EPERM, _RET_ERRNO | errno.ENOSYS
    out = [_ins(_LD_W_ABS, 4), _ins(_JEQ_K, arch, 1, 0), _ins(_RET_K, _RET_KILL),  # a foreign ABI: kill
           _ins(_LD_W_ABS, 0)]
    if machine == "x86_64":  # the x32 ABI numbers the same calls differently: refuse all of it
        out += [_ins(_JSET_K, _X32_BIT, 0, 1), _ins(_RET_K, eperm)]
    for name in REFUSED:
        if name in nr:
            out += [_ins(_JEQ_K, nr[name], 0, 1), _ins(_RET_K, eperm)]
    out += [_ins(_JEQ_K, nr["clone3"], 0, 1), _ins(_RET_K, enosys),
            _ins(_JEQ_K, nr["clone"], 0, 3), _ins(_LD_W_ABS, 16),  # clone(flags, ...): the low word of flags
            _ins(_JSET_K, _CLONE_THREAD, 1, 0), _ins(_RET_K, eperm),
            _ins(_RET_K, _RET_ALLOW)]
    return b"".join(out)


class _Fprog(ctypes.Structure):
    _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]


def install() -> None:
    """Install the filter on this process (and all its future threads); raises ``OSError``."""
    prog = program()
    buf = ctypes.create_string_buffer(prog, len(prog))
    fprog = _Fprog(len(prog) // 8, ctypes.cast(buf, ctypes.c_void_p))
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl.argtypes = [ctypes.c_int, ctypes.c_ulong, ctypes.c_void_p, ctypes.c_ulong, ctypes.c_ulong]
    if libc.prctl(_PR_SET_NO_NEW_PRIVS, 1, None, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_NO_NEW_PRIVS) failed")
    if libc.prctl(_PR_SET_SECCOMP, _SECCOMP_MODE_FILTER, ctypes.addressof(fprog), 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_SECCOMP) failed")


__all__ = ["ARCHES", "REFUSED", "install", "program"]
