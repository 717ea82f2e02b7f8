"""Starting the rerun viewer on an episode log (``--open``), or explaining how when there is no
display (``--web`` serves the web viewer instead, e.g. over SSH port forwarding).

The viewer is the one installed with the running Python (``rerun`` next to ``sys.executable``,
else ``python -m rerun_cli`` from the same environment), never whatever ``rerun`` is first on
PATH: an un-activated virtualenv must still find its own, version-matched viewer.  ``--new``
makes it a new window even when a viewer is already running.
"""

from __future__ import annotations

import importlib.util
import os
import shlex
import subprocess
import sys
from pathlib import Path
from typing import Sequence

WEB_PORT = 9090
GRPC_PORT = 9876


def viewer_command() -> list[str] | None:
    """The command that runs this environment's rerun viewer, or None when it is not installed."""
    exe = Path(sys.executable).parent / ("rerun.exe" if os.name == "nt" else "rerun")
    if exe.is_file() and os.access(exe, os.X_OK):
        return [str(exe)]
    if importlib.util.find_spec("rerun_cli") is not None:
        return [sys.executable, "-m", "rerun_cli"]
    return None


def has_display() -> bool:
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def web_instructions(path: str | Path) -> str:
    """How to look at ``path`` from another machine's browser."""
    here = f"{shlex.quote(sys.executable)} -m capmj.replay {shlex.quote(str(path))} --web"
    return (f"No display here (DISPLAY/WAYLAND_DISPLAY unset), so no viewer window can open.\n"
            f"Use the web viewer over SSH port forwarding:\n"
            f"  1. on this machine:  {here}\n"
            f"  2. on your computer: ssh -N -L {WEB_PORT}:localhost:{WEB_PORT} -L {GRPC_PORT}:localhost:{GRPC_PORT} "
            f"<this host>\n"
            f"  3. open http://localhost:{WEB_PORT} in your browser.\n"
            f"Or copy the file to your computer and run: python -m capmj.replay {Path(path).name} --open")


def _run(cmd: Sequence[str]) -> int:
    try:
        return subprocess.call(list(cmd))
    except OSError as exc:
        print(f"capmj-replay: could not start the rerun viewer ({cmd[0]}): {exc}", file=sys.stderr)
        return 1


def _missing() -> int:
    print("capmj-replay: the rerun viewer is not installed in this Python environment "
          f"({sys.executable}); install it with: {sys.executable} -m pip install 'rerun-sdk==0.41.*'",
          file=sys.stderr)
    return 1


def open_viewer(path: str | Path) -> int:
    """Open ``path`` in a new viewer window (blocks until it is closed); without a display print
    :func:`web_instructions` and return 0."""
    if not has_display():
        print(web_instructions(path))
        return 0
    cmd = viewer_command()
    if cmd is None:
        return _missing()
    return _run([*cmd, "--new", str(path)])


def serve_web(path: str | Path) -> int:
    """Serve the web viewer with ``path`` on ports 9090 (page) and 9876 (data); blocks."""
    cmd = viewer_command()
    if cmd is None:
        return _missing()
    print(f"serving {path}: open http://localhost:{WEB_PORT} (forward ports {WEB_PORT} and {GRPC_PORT} over SSH); "
          "Ctrl-C stops", flush=True)
    return _run([*cmd, "--serve-web", "--web-viewer-port", str(WEB_PORT), "--port", str(GRPC_PORT), str(path)])


__all__ = ["GRPC_PORT", "WEB_PORT", "has_display", "open_viewer", "serve_web", "viewer_command", "web_instructions"]
