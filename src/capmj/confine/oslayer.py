"""The OS layer: the check worker in its own network and mount namespace, file system read-only.

Where Linux allows it (root, or unprivileged user namespaces), the child process — between
``fork`` and ``exec``, before any generated code exists in it — leaves the machine's network
(a new network namespace has only a loopback device, and that one is down) and gets a private
copy of the mount table in which every mount is remounted read-only.  Even code that got past
the static check and the audit hook can then neither reach another host nor change a file.

It is a layer, not the wall: where namespaces are not permitted (some containers), the worker
runs without it and the run records why.  Everything here runs in the forked child, so a
failure is reported on the events descriptor instead of raised (an exception in a
``preexec_fn`` would only surface as an opaque ``SubprocessError``).
"""

from __future__ import annotations

import ctypes
import json
import os
from typing import Callable

CLONE_NEWNS, CLONE_NEWNET, CLONE_NEWUSER = 0x00020000, 0x40000000, 0x10000000
MS_RDONLY, MS_NOSUID, MS_NODEV, MS_NOEXEC = 1, 2, 4, 8
MS_REMOUNT, MS_BIND, MS_NOATIME, MS_NODIRATIME, MS_RELATIME = 32, 4096, 1024, 2048, 1 << 21
MS_REC, MS_PRIVATE = 16384, 1 << 18
_KEEP = {os.ST_NOSUID: MS_NOSUID, os.ST_NODEV: MS_NODEV, os.ST_NOEXEC: MS_NOEXEC, os.ST_NOATIME: MS_NOATIME,
         os.ST_NODIRATIME: MS_NODIRATIME, os.ST_RELATIME: MS_RELATIME}
"""Flags a bind remount must repeat (in a user namespace they are locked, and dropping one fails)."""


def _libc() -> ctypes.CDLL:
    return ctypes.CDLL(None, use_errno=True)


def _check(rc: int, what: str) -> None:
    if rc != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"{what}: {os.strerror(err)}")


def _enter_namespaces(libc: ctypes.CDLL) -> str:
    """New mount and network namespaces, through a user namespace when not root."""
    if os.geteuid() == 0:
        _check(libc.unshare(CLONE_NEWNS | CLONE_NEWNET), "unshare(mount, net)")
        return "root"
    uid, gid = os.geteuid(), os.getegid()
    _check(libc.unshare(CLONE_NEWUSER | CLONE_NEWNS | CLONE_NEWNET), "unshare(user, mount, net)")
    for name, text in (("setgroups", "deny"), ("uid_map", f"{uid} {uid} 1"), ("gid_map", f"{gid} {gid} 1")):
        with open(f"/proc/self/{name}", "w") as f:
            f.write(text)
    return "user namespace"


def _mount_points() -> list[str]:
    points = []
    with open("/proc/self/mountinfo", encoding="utf-8") as f:
        for line in f:
            raw = line.split()[4]
            points.append(raw.encode().decode("unicode_escape"))  # \040 for a space, etc.
    return points


def _read_only(libc: ctypes.CDLL) -> list[str]:
    """Remount every mount read-only in this (private!) mount namespace; returns those that stay writable."""
    _check(libc.mount(None, b"/", None, MS_REC | MS_PRIVATE, None), "make / private")
    left = []
    for mp in _mount_points():
        try:
            st = os.statvfs(mp)
        except OSError:
            continue
        keep = sum(ms for st_flag, ms in _KEEP.items() if st.f_flag & st_flag)
        rc = libc.mount(None, mp.encode(), None, MS_REMOUNT | MS_BIND | MS_RDONLY | keep, None)
        if rc != 0 and not os.statvfs(mp).f_flag & os.ST_RDONLY:
            left.append(mp)
    return left


def confine_child(events_fd: int) -> Callable[[], None]:
    """A ``preexec_fn`` that enters the namespaces and reports what it achieved on ``events_fd``."""
    def apply() -> None:
        report: dict[str, object] = {"network": False, "read_only": False}
        try:
            libc = _libc()
            report["via"] = _enter_namespaces(libc)
            report["network"] = True  # the namespace exists from here on; its loopback is down
            left = _read_only(libc)
            report["read_only"] = not left
            if left:
                report["writable"] = left[:8]
        except Exception as e:  # noqa: BLE001 - reported, never raised across the fork
            report["error"] = f"{type(e).__name__}: {e}"
        os.write(events_fd, (json.dumps({"os_layer": report}) + "\n").encode())
    return apply


__all__ = ["confine_child"]
