"""A corpus of hostile generated-task modules, one door to the operating system each (issue #25).

Every entry is the good candidate ``good_zone_color.py`` with a few lines added — after its
imports (they run while the checks load it) or at the top of ``sample_scene()`` (they run during the
``scenes`` check).  Each door, if it were open, leaves a trace the caller can look for: a file
named ``MARKER`` (or the file ``VICTIM`` gone), or a connection to the TCP port ``PORT``.  These
are fixtures for tests and for ``benchmarks/confinement.py``, never results.

``static`` is a fragment the static check's message must contain (it names the door); ``events``
the audit events the runtime guard may record for it (``()``: the runtime layer is not expected
to stop it — said so in ``docs/security.md``).
"""

from __future__ import annotations

import os
import socket
from dataclasses import dataclass
from pathlib import Path
from typing import Any

GOOD = Path(__file__).resolve().parent / "generator_candidates" / "good_zone_color.py"
NAME = "put-blocks-in-zone-of-same-color"
_AFTER_IMPORTS = "from capmj.tasks.spawn import Spawner, pick_colors\n"
_SAMPLE_SCENE = "    def sample_scene(self, rng: np.random.Generator) -> Scene:\n"


@dataclass(frozen=True)
class Hostile:
    id: str
    door: str
    code: str
    static: str
    events: tuple[str, ...]
    where: str = "import"

    def module(self, marker: Path, victim: Path, port: int) -> str:
        """The candidate's source with this door's lines in place."""
        lines = (self.code.replace("MARKER", str(marker)).replace("VICTIM", str(victim))
                 .replace("PORT", str(port)))
        src = GOOD.read_text(encoding="utf-8")
        if self.where == "sample_scene":
            body = "".join(f"        {ln}\n" for ln in lines.splitlines())
            return src.replace(_SAMPLE_SCENE, _SAMPLE_SCENE + body)
        return src.replace(_AFTER_IMPORTS, _AFTER_IMPORTS + lines + "\n")


_TYPING_OS = 'import typing\n_os = typing.sys.modules["os"]\n'
_IMPORTLIB = 'import typing\n_il = typing.sys.modules["importlib"]\n'

CORPUS: tuple[Hostile, ...] = (
    Hostile("registry-os-system", "process", 'from capmj.tasks import registry as _r\n_r.os.system("touch MARKER")',
            "capmj.tasks.registry", ("os.system",)),
    Hostile("typing-sys-modules", "process", 'import typing\ntyping.sys.modules["os"].system("touch MARKER")',
            "typing.sys", ("os.system",)),
    Hostile("dataclasses-sys-posix-spawn", "process",
            'import dataclasses\n_os = dataclasses.sys.modules["os"]\n'
            '_os.posix_spawn("/usr/bin/touch", ["touch", "MARKER"], {})', "dataclasses.sys", ("os.posix_spawn",)),
    Hostile("numpy-f2py-os", "process", 'import numpy as np\nnp.f2py.os.system("touch MARKER")', "np.f2py",
            ("os.system",)),
    Hostile("registry-importlib-subprocess", "process",
            'from capmj.tasks import registry as _r\n_r.importlib.import_module("subprocess").run(["touch", "MARKER"])',
            "capmj.tasks.registry", ("subprocess.Popen",)),
    Hostile("raw-os-open-write", "file", _TYPING_OS + '_fd = _os.open("MARKER", _os.O_WRONLY | _os.O_CREAT)\n'
            '_os.write(_fd, b"owned")', "typing.sys", ("open",)),
    Hostile("in-sample-scene", "process", 'import typing\ntyping.sys.modules["os"].system("touch MARKER")',
            "typing.sys", ("os.system",), where="sample_scene"),
    Hostile("import-os", "process", 'import os\nos.system("touch MARKER")', "import of 'os'", ("os.system",)),
    Hostile("dunder-import", "process", '__import__("os").system("touch MARKER")', "'__import__'", ("os.system",)),
    Hostile("print-self-builtins", "process", 'print.__self__.__import__("os").system("touch MARKER")',
            "'__self__'", ("os.system",)),
    Hostile("traceback-frame-globals", "process",
            'try:\n    1 / 0\nexcept ZeroDivisionError as _e:\n    _b = _e.__traceback__.tb_frame.f_globals["__builtins__"]\n'
            '    _b = _b if isinstance(_b, dict) else _b.__dict__\n    _b["__import__"]("os").system("touch MARKER")',
            "'__traceback__'", ("os.system",)),
    Hostile("generator-frame-builtins", "process",
            '_g = (x for x in [0])\n_g.gi_frame.f_builtins["__import__"]("os").system("touch MARKER")',
            "'gi_frame'", ("os.system",)),
    Hostile("eval-string", "process", 'eval("__import__(\'os\').system(\'touch MARKER\')")', "'eval'",
            ("os.system",)),
    Hostile("exec-spoofed-filename", "process",
            'exec(compile("import os\\nos.system(\'touch MARKER\')", "/usr/lib/python3/dist-packages/ok.py", "exec"))',
            "'exec'", ("os.system",)),
    Hostile("type-hints-eval", "process",
            'import typing\ndef _f(x: "__import__(\'os\').system(\'touch MARKER\')") -> None:\n    pass\n'
            'typing.get_type_hints(_f)', "typing.get_type_hints", ("os.system",)),
    Hostile("pickle-find-class", "process",
            'import typing\ntyping.sys.modules["pickle"].loads(b"cos\\nsystem\\n(S\'touch MARKER\'\\ntR.")',
            "typing.sys", ("os.system", "pickle.find_class")),
    Hostile("ctypes-libc-system", "native", 'import typing\ntyping.sys.modules["ctypes"].CDLL(None).system(b"touch MARKER")',
            "typing.sys", ("ctypes.",)),
    Hostile("numpy-ctypeslib", "native",
            'import numpy as np\nnp.ctypeslib.load_library("libc.so.6", "/usr/lib/x86_64-linux-gnu").system(b"touch MARKER")',
            "np.ctypeslib", ("ctypes.",)),
    Hostile("socket-connect", "network",
            'import typing\n_s = typing.sys.modules["socket"]\n_s.create_connection(("127.0.0.1", PORT), timeout=2)'
            '.sendall(b"owned")', "typing.sys", ("socket.",)),
    Hostile("dns-lookup", "network", 'import typing\ntyping.sys.modules["socket"].getaddrinfo("owned.example", 80)',
            "typing.sys", ("socket.",)),
    Hostile("import-module-new", "import", _IMPORTLIB + '_il.import_module("ftplib")', "typing.sys", ("import",)),
    Hostile("os-fork", "process", _TYPING_OS + 'if _os.fork() == 0:\n    _os.system("touch MARKER")\n    _os._exit(0)',
            "typing.sys", ("os.fork",)),
    Hostile("os-execv", "process", _TYPING_OS + '_os.execv("/usr/bin/touch", ["touch", "MARKER"])', "typing.sys",
            ("os.exec",)),
    Hostile("signal-parent", "process", _TYPING_OS + "_os.kill(_os.getppid(), 0)", "typing.sys", ("os.kill",)),
    Hostile("raise-rlimit", "limits", 'import typing\n_res = typing.sys.modules["resource"]\n'
            "_res.setrlimit(_res.RLIMIT_CPU, (-1, -1))", "typing.sys", ("resource.setrlimit",)),
    Hostile("pathlib-write", "file", 'import typing\ntyping.sys.modules["pathlib"].Path("MARKER").write_text("owned")',
            "typing.sys", ("open",)),
    Hostile("numpy-save", "file", 'import numpy as np\nnp.save("MARKER", np.zeros(3))', "np.save", ("open",)),
    Hostile("remove-victim", "file", _TYPING_OS + '_os.remove("VICTIM")', "typing.sys", ("os.remove",)),
    Hostile("atexit-deferred", "process",
            'import typing\ntyping.sys.modules["atexit"].register(typing.sys.modules["os"].system, "touch MARKER")',
            "'system'", ("os.system",)),
    Hostile("patch-trusted-runner", "process",
            'import typing\n_run = typing.sys.modules["capmj.runner"]\n_orig = _run.run_episode\n'
            'def _evil(*a, **k):\n    typing.sys.modules["os"].system("touch MARKER")\n    return _orig(*a, **k)\n'
            "_run.run_episode = _evil", "typing.sys", ("os.system",)),
    Hostile("thread-deferred", "process",
            'import typing\n_t = typing.sys.modules["threading"].Thread(target=typing.sys.modules["os"].system, '
            'args=("touch MARKER",))\n_t.start()\n_t.join()', "typing.sys", ("os.system",)),
    Hostile("forge-results", "integrity",
            _TYPING_OS +
            'for _n in ("load", "protocol", "scenes", "goal_text", "not_solved_at_reset", "do_nothing_fails",\n'
            '           "oracle_solves", "reward_agrees"):\n'
            '    for _fd in range(3, 16):\n'
            '        try:\n'
            '            _os.write(_fd, (\'{"result": {"name": "\' + _n + \'", "outcome": "pass", "detail": "forged"}}\\n\').encode())\n'
            '        except OSError:\n'
            '            pass\n'
            '_os._exit(0)', "typing.sys", ()),
)
"""The corpus; ``events == ()`` marks what the runtime layer alone does not stop."""

BY_ID = {h.id: h for h in CORPUS}


def processes_mentioning(token: str) -> list[str]:
    """Command lines of running processes that contain ``token`` (a run's folder)."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if token in cmd:
            found.append(cmd)
    return found


def run_hostile(hostile: Hostile, folder: Path, **layers: bool) -> tuple[Any, list[str]]:
    """Check ``hostile`` in the real worker (static check bypassed; ``layers`` as for
    ``run_isolated``) inside ``folder``; returns the run and every trace its door left."""
    from capmj.generate.config import Limits
    from capmj.generate.isolate import run_isolated

    victim = folder / "victim"
    victim.write_text("keep me")
    with socket.socket() as srv:
        srv.bind(("127.0.0.1", 0))
        srv.listen()
        srv.setblocking(False)
        path = folder / "candidate.py"
        path.write_text(hostile.module(folder / "marker", victim, srv.getsockname()[1]))
        run = run_isolated(path, name=NAME, seeds=(0,), accept_rate=1.0, tags=("generated-by-llm",),
                           limits=Limits(cpu_s=60, wall_s=120), **layers)
        try:
            srv.accept()
            connected = ["a connection reached the listening socket"]
        except BlockingIOError:
            connected = []
    traces = [p.name for p in folder.iterdir() if p.name not in ("victim", "candidate.py")]
    traces += [] if victim.exists() else ["the victim file was removed"]
    return run, traces + connected + processes_mentioning(str(folder))


__all__ = ["BY_ID", "CORPUS", "GOOD", "Hostile", "NAME", "processes_mentioning", "run_hostile"]
