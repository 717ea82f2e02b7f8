"""Headless OpenGL backend selection for MuJoCo rendering (EGL first, then OSMesa), when rendering starts.

MuJoCo's Python bindings pick their OpenGL backend **once, when ``mujoco`` is first imported**, from
the ``MUJOCO_GL`` environment variable (``egl``, ``osmesa``, ``glfw``...); PyOpenGL likewise fixes
its platform at its first import.  A ``MUJOCO_GL`` naming a backend whose library is missing makes
``import mujoco`` itself fail (e.g. ``MUJOCO_GL=osmesa`` without ``libosmesa6``).

Nothing here runs at import: importing capmj sets no variable and starts no probe (the default
used to be set when ``capmj.sim`` was imported, so that merely importing the simulator changed the
process's environment).  The backend is settled when rendering starts, by :func:`shared_gl_context`
(the first :class:`~capmj.sim.cameras.CameraRig`) through :func:`ensure_gl_backend`:

- a ``MUJOCO_GL`` the user set is used as given, and verified when the context is created;
- otherwise, if mujoco is not imported yet (a script may call :func:`ensure_gl_backend` first, as
  ``benchmarks/render.py`` does), EGL and then OSMesa are probed, each in a short subprocess that
  creates a tiny GL context exactly the way MuJoCo does, and ``MUJOCO_GL`` is set to the first that
  works;
- if mujoco was imported without ``MUJOCO_GL`` (the usual case: the world imports it), it chose GLFW;
  with a display that is used, and a headless process gets ``mujoco.egl``/``mujoco.osmesa`` loaded
  directly after the same probe (:func:`_resolve_imported`).  Setting ``MUJOCO_GL=egl`` before
  mujoco is imported skips the probe (one subprocess, ~1 s, once per process).

Every failure raises :class:`~capmj.errors.RenderBackendError` naming the apt packages and the
``MUJOCO_GL`` values.  One GL context is shared by the whole process (creating one costs 0.2-1 s);
each :class:`~capmj.sim.cameras.CameraRig` makes its own ``MjrContext`` on it.  The context and
every registered rig are freed explicitly at interpreter exit (before MuJoCo's own ``atexit`` EGL
teardown), which avoids the tracebacks EGL/OSMesa print when contexts are garbage-collected late.
"""

from __future__ import annotations

import atexit
import ctypes
import importlib
import os
import subprocess
import sys
import threading
import weakref
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Callable, Iterator

from capmj.errors import RenderBackendError

BACKENDS: tuple[str, ...] = ("egl", "osmesa")
"""Headless backends tried, in order."""
APT_PACKAGES = "libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6"
INSTALL_HINT = (
    f"install the Mesa headless GL libraries (apt-get install -y {APT_PACKAGES}) and set "
    "MUJOCO_GL=egl (or MUJOCO_GL=osmesa for pure-software OSMesa) before anything imports mujoco"
)
_LIBRARIES: dict[str, tuple[str, ...]] = {
    "egl": ("libEGL.so.1", "libEGL.so"),
    "osmesa": ("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"),
}
_PROBE_CODE = (
    "import mujoco\n"
    "ctx = mujoco.GLContext(8, 8)\n"
    "ctx.make_current()\n"
    "ctx.free()\n"
)
_PROBE_TIMEOUT_S = 60.0



@dataclass
class GLState:
    """Everything this module remembers in a process (one instance, :data:`STATE`)."""

    chosen: str | None = None
    """The backend :func:`ensure_gl_backend` settled on."""
    probe_results: dict[str, tuple[bool, str]] = field(default_factory=dict)
    shared_context: Any = None
    context_pid: int = -1
    """The process that created ``shared_context`` (a forked child must not use it)."""
    cleanups: list[weakref.finalize] = field(default_factory=list)
    atexit_registered: bool = False


STATE = GLState()

RENDER_LOCK = threading.RLock()
"""One thread at a time draws with the process's one GL context (episodes run in threads)."""


def library_loadable(backend: str) -> bool:
    """Whether the shared library of ``backend`` can be ``dlopen``-ed (cheap, creates no context)."""
    for name in _LIBRARIES.get(backend, ()):
        try:
            ctypes.CDLL(name)
            return True
        except OSError:
            continue
    return False


def probe_backend(backend: str) -> tuple[bool, str]:
    """Create a tiny GL context with ``backend`` in a subprocess; (works, reason if not).  Cached."""
    if backend in STATE.probe_results:
        return STATE.probe_results[backend]
    if not library_loadable(backend):
        result = (False, f"{_LIBRARIES[backend][0]} not found")
    else:
        env = dict(os.environ, MUJOCO_GL=backend)
        env.pop("PYOPENGL_PLATFORM", None)  # mujoco sets it to match MUJOCO_GL
        try:
            proc = subprocess.run([sys.executable, "-c", _PROBE_CODE], env=env, capture_output=True,
                                  text=True, timeout=_PROBE_TIMEOUT_S)
            ok = proc.returncode == 0
            lines = [ln for ln in proc.stderr.strip().splitlines() if ln.strip()]
            result = (ok, "" if ok else (lines[-1] if lines else f"exit code {proc.returncode}"))
        except (OSError, subprocess.TimeoutExpired) as exc:
            result = (False, f"probe failed: {exc}")
    STATE.probe_results[backend] = result
    return result


def imported_backend() -> str | None:
    """The backend the already-imported mujoco chose (``egl``, ``osmesa``, ``glfw``...), or None."""
    gl_context = _mujoco_gl_module()
    ctx = getattr(gl_context, "GLContext", None) if gl_context is not None else None
    return None if ctx is None else ctx.__module__.rsplit(".", 1)[-1]


def _mujoco_gl_module() -> Any:
    try:
        from mujoco.rendering.classic import gl_context
    except ImportError:  # pragma: no cover - older mujoco layout
        try:
            from mujoco import gl_context  # type: ignore[no-redef]
        except ImportError:
            return None
    return gl_context


def _resolve_imported() -> tuple[str, Any]:
    """(backend, GLContext class) to use in this process, mujoco being imported.

    Normally the class mujoco chose at import.  When mujoco fell back to GLFW (``MUJOCO_GL`` unset
    at import) and there is no display, the headless classes ``mujoco.egl``/``mujoco.osmesa`` can
    still be loaded as long as PyOpenGL has not been imported with another platform (mujoco's GLFW
    path does not import PyOpenGL); the first backend whose subprocess probe succeeds is used.
    """
    backend = imported_backend()
    if backend in BACKENDS:
        return backend, importlib.import_module(f"mujoco.{backend}").GLContext
    module = _mujoco_gl_module()
    at_import = getattr(module, "_MUJOCO_GL", os.environ.get("MUJOCO_GL", "")) or "<unset>"
    if backend is not None and "DISPLAY" in os.environ:
        return backend, module.GLContext  # a desktop session: mujoco's own choice works
    platform = os.environ.get("PYOPENGL_PLATFORM", "").strip().lower()
    pyopengl_loaded = any(m == "OpenGL" or m.startswith("OpenGL.") for m in sys.modules)
    candidates = BACKENDS if not (platform or pyopengl_loaded) else tuple(b for b in BACKENDS if b == platform)
    reasons = []
    for b in candidates:
        ok, reason = probe_backend(b)
        if not ok:
            reasons.append(f"{b}: {reason}")
            continue
        try:
            return b, importlib.import_module(f"mujoco.{b}").GLContext
        except Exception as exc:  # e.g. PyOpenGL already bound to another platform
            reasons.append(f"{b}: {type(exc).__name__}: {exc}")
    if not candidates:
        reasons.append(f"PyOpenGL is already loaded with PYOPENGL_PLATFORM={platform or '<unset>'!r}")
    raise RenderBackendError(
        f"mujoco was imported with MUJOCO_GL={at_import!r} ({backend or 'no'} GL backend), which needs a "
        f"display, and no headless backend could be loaded afterwards ({'; '.join(reasons)}). Set "
        f"MUJOCO_GL=egl or MUJOCO_GL=osmesa before mujoco is first imported; if neither works, {INSTALL_HINT}")


def ensure_gl_backend() -> str:
    """Make sure a headless GL backend is selected; return its name (``"egl"``/``"osmesa"``...).

    Rendering calls it when it starts; a script may call it before anything imports mujoco.  If
    mujoco is not imported yet and ``MUJOCO_GL`` is unset, EGL then OSMesa are probed and
    ``MUJOCO_GL`` is set to the first that works.  If mujoco is already imported, its backend is fixed: the one chosen at
    import is used, except that a headless process whose mujoco fell back to GLFW gets EGL/OSMesa
    loaded directly (see :func:`_resolve_imported`).  Raises :class:`RenderBackendError` when no
    backend can work.
    """
    if STATE.chosen is not None:
        return STATE.chosen
    if "mujoco" in sys.modules:
        STATE.chosen = _resolve_imported()[0]
        return STATE.chosen
    requested = os.environ.get("MUJOCO_GL", "").strip().lower()
    if requested:
        STATE.chosen = requested  # the user's explicit choice; verified when the context is created
        return requested
    reasons = []
    for backend in BACKENDS:
        ok, reason = probe_backend(backend)
        if ok:
            os.environ["MUJOCO_GL"] = backend
            STATE.chosen = backend
            return backend
        reasons.append(f"{backend}: {reason}")
    raise RenderBackendError(f"no headless OpenGL backend works ({'; '.join(reasons)}); {INSTALL_HINT}")


def _context_failure(backend: str, exc: BaseException) -> RenderBackendError:
    others = [b for b in BACKENDS if b != backend and probe_backend(b)[0]]
    alt = (f" MUJOCO_GL={others[0]} works on this machine: set it before mujoco is imported."
           if others else "")
    return RenderBackendError(f"cannot create an OpenGL context with the {backend} backend "
                              f"({type(exc).__name__}: {exc}).{alt} Otherwise {INSTALL_HINT}")


def shared_gl_context() -> Any:
    """The process-wide MuJoCo ``GLContext``, created on first use and made current.

    Raises :class:`RenderBackendError` when it cannot be created.
    """
    if STATE.shared_context is not None and STATE.context_pid != os.getpid():
        # Measured: with Mesa (llvmpipe, EGL and OSMesa) a child forked after its parent made a GL
        # context hangs forever in its first GL call, even with a fresh context.  Fail instead.
        raise RenderBackendError(
            "this process was forked after its parent created an OpenGL context; Mesa cannot render "
            "in such a child (it deadlocks). Start rendering workers with multiprocessing's 'spawn' or "
            "'forkserver' method, or do not render in the parent before forking.")
    if STATE.shared_context is not None:
        STATE.shared_context.make_current()
        return STATE.shared_context
    backend = ensure_gl_backend()
    try:
        import mujoco  # noqa: F401
    except Exception as exc:  # a MUJOCO_GL naming a missing library breaks the import itself
        raise _context_failure(backend, exc) from exc
    backend, ctx_cls = _resolve_imported()
    try:
        ctx = ctx_cls(640, 480)  # size only matters for OSMesa's window buffer; rendering uses FBOs
        ctx.make_current()
    except Exception as exc:
        raise _context_failure(backend, exc) from exc
    STATE.shared_context = ctx
    STATE.context_pid = os.getpid()
    if not STATE.atexit_registered:
        atexit.register(release_gl)  # runs before mujoco.egl's eglTerminate (registered earlier)
        STATE.atexit_registered = True
    return ctx


def release_current() -> None:
    """Let go of the shared context in this thread, so that another thread can make it current: an
    EGL context is current in one thread at a time, and a thread that keeps it (a pool's worker
    thread lives on) would lock every other thread out.  No GL call in a forked child."""
    ctx = STATE.shared_context
    if ctx is None or STATE.context_pid != os.getpid() or type(ctx).__module__ != "mujoco.egl":
        return
    egl = sys.modules["mujoco.egl"]
    egl.EGL.eglMakeCurrent(egl.EGL_DISPLAY, egl.EGL.EGL_NO_SURFACE, egl.EGL.EGL_NO_SURFACE, egl.EGL.EGL_NO_CONTEXT)


@contextmanager
def current_context() -> Iterator[Any]:
    """The shared context, current in this thread for the block's GL calls and released after them,
    one thread at a time (:data:`RENDER_LOCK`).  Raises :class:`RenderBackendError` as
    :func:`shared_gl_context` does."""
    with RENDER_LOCK:
        ctx = shared_gl_context()
        try:
            yield ctx
        finally:
            release_current()


def make_current() -> bool:
    """Make the shared context current if this process owns one; False otherwise (no GL call made)."""
    if STATE.shared_context is None or STATE.context_pid != os.getpid():
        return False
    try:
        STATE.shared_context.make_current()
        return True
    except Exception:  # pragma: no cover - best effort
        return False


def register_cleanup(owner: object, fn: Callable[..., None], *args: Any) -> weakref.finalize:
    """Call ``fn(*args)`` when ``owner`` is collected or before the shared context is released.

    ``fn`` must not reference ``owner``.  Used by camera rigs to free their ``MjrContext`` while
    the GL context is still alive.
    """
    fin = weakref.finalize(owner, fn, *args)
    fin.atexit = False  # release_gl() runs it in the right order instead
    STATE.cleanups[:] = [f for f in STATE.cleanups if f.alive]
    STATE.cleanups.append(fin)
    return fin


def release_gl() -> None:
    """Free every registered GPU resource, then the shared context (idempotent; run at exit)."""
    if STATE.context_pid != os.getpid():
        return  # a forked child must not free its parent's GL objects
    ctx = STATE.shared_context
    if ctx is not None:
        try:
            ctx.make_current()
        except Exception:  # pragma: no cover - best effort at shutdown
            pass
    while STATE.cleanups:
        fin = STATE.cleanups.pop()
        try:
            fin()
        except Exception:  # pragma: no cover - best effort at shutdown
            pass
    if ctx is not None:
        STATE.shared_context = None
        try:
            ctx.free()
        except Exception:  # pragma: no cover
            pass
