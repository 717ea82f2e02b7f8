"""Fresh virtualenvs for tests that install a package and run it in a separate interpreter.

Why not ``python -m venv --system-site-packages``: that option exposes the *base* interpreter's
site-packages.  When pytest itself runs in a virtualenv (as on every system whose Python is
externally managed), capmj's dependencies live in that virtualenv, not in the base, and the new
venv would fail at ``import mujoco``.  Instead the new venv gets a ``.pth`` file that adds every
site directory the running interpreter has on ``sys.path`` -- the virtualenv's, the system's, the
user's, whichever are in use -- after its own site-packages, so what is installed into the new venv
(a wheel, a generated plugin) wins and the heavy dependencies are borrowed, not reinstalled.

The venv is made ``--without-pip`` (fast, and no ``ensurepip`` needed); packages go in with the
running interpreter's pip (``pip --python``).  What the venv must own (a wheel of capmj itself) is
installed *before* the ``.pth`` exists: afterwards pip would see the running environment's capmj of
the same version and skip the install as "already satisfied".
"""

from __future__ import annotations

import os
import site
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

PTH = "zz_parent_env.pth"
"""Name of the ``.pth`` file; ``zz`` so it is read after any other ``.pth`` of the new venv."""


def parent_site_dirs() -> list[str]:
    """The running interpreter's site directories that are on its ``sys.path``, in ``sys.path`` order."""
    candidates = [*site.getsitepackages(), site.getusersitepackages()]
    on_path = [os.path.abspath(p) for p in sys.path]
    wanted = {os.path.abspath(d) for d in candidates if os.path.isdir(d)}
    seen: list[str] = []
    for p in on_path:
        if p in wanted and p not in seen:
            seen.append(p)
    return seen


def make_venv(path: Path, own: Sequence[str] = ()) -> Path:
    """Create a virtualenv at ``path`` holding the packages ``own`` (wheel files, installed offline
    without dependencies) that borrows everything else from this interpreter; return its python."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(path)], check=True, timeout=120)
    py = path / "bin" / "python"
    if own:
        pip = pip_install(py, *own)
        if pip.returncode != 0:
            raise RuntimeError(f"pip install {' '.join(own)} into {path} failed:\n{pip.stderr}")
    target = subprocess.run([str(py), "-c", "import site; print(site.getsitepackages()[0])"], capture_output=True,
                            text=True, check=True, timeout=60).stdout.strip()
    lines = "".join(f"import site; site.addsitedir({d!r})\n" for d in parent_site_dirs())
    Path(target, PTH).write_text(lines)
    return py


def pip_install(py: Path, *args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """``pip install`` into the venv of ``py`` with the running interpreter's pip, offline.

    ``PYTHONPATH`` is dropped (unless ``env`` is given): pip would count a source tree on it as an
    installed capmj and skip the install."""
    if env is None:
        env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    cmd = [sys.executable, "-m", "pip", "--python", str(py), "install", "--quiet", "--no-deps", "--no-index",
           "--disable-pip-version-check", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
