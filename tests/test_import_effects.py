"""Importing capmj does nothing: no environment variable, no subprocess, no registration.

Each module of the package is imported, in one fresh interpreter, under an audit hook that records
every process start and every ``os.putenv`` done by capmj's code (the innermost caller outside the
standard library is a capmj file; what a third-party library does at its own import is not ours);
the environment, the signal handlers, ``sys.path``, the Gymnasium registry and capmj's task
registry are compared before and after.  Work belongs to
the call that needs it: the GL backend is chosen when rendering starts, Gymnasium ids are
registered by ``capmj.envs.register()``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "src" / "capmj"

ALLOWED = {
    "capmj.envs.gym_ids": "registers capmj/<task>-v0 with Gymnasium at import: Gymnasium's "
                          "'module:env-id' form imports a module for exactly that (docs/learning.md)",
}
"""Modules whose import does work on purpose, with the reason; imported last, checked apart."""

_PROBE = r"""
import importlib, json, os, signal, sys, sysconfig
modules = json.loads(sys.argv[1])
STDLIB = sysconfig.get_paths()["stdlib"]
events, foreign, foreign_env = [], [], set()
def culprit():
    # the innermost caller outside the standard library: whose doing an event is
    f = sys._getframe(2)
    while f is not None and (f.f_code.co_filename.startswith((STDLIB, "<")) and "site-packages" not in f.f_code.co_filename):
        f = f.f_back
    return f.f_code.co_filename if f is not None else "?"
def hook(event, args):
    if event in ("subprocess.Popen", "os.system", "os.posix_spawn", "os.spawn", "os.exec", "os.fork",
                 "os.forkpty", "os.putenv", "os.unsetenv"):
        who = culprit()
        line = f"{event} {str(args)[:200]} by {who}"
        if "capmj" in who:
            events.append(line)
        else:  # a third-party library's own import-time work (numpy's OPENBLAS_MAIN_FREE...)
            foreign.append(line)
            if event in ("os.putenv", "os.unsetenv"):
                foreign_env.add(os.fsdecode(args[0]))
sys.addaudithook(hook)
import gymnasium
env, path = dict(os.environ), list(sys.path)
handlers = {s.name: repr(signal.getsignal(s)) for s in signal.valid_signals() if hasattr(s, "name")}
gym_ids = set(gymnasium.registry)
failed = {}
for name in modules:
    try:
        importlib.import_module(name)
    except Exception as exc:
        failed[name] = f"{type(exc).__name__}: {exc}"
from capmj.tasks import registry
print(json.dumps({
    "events": events, "failed": failed, "foreign": foreign,
    "env_changed": sorted(k for k in set(env) | set(os.environ)
                          if env.get(k) != os.environ.get(k) and k not in foreign_env),
    "sys_path_changed": path != sys.path,
    "signals_changed": sorted(s.name for s in signal.valid_signals() if hasattr(s, "name")
                              and handlers[s.name] != repr(signal.getsignal(s))),
    "gym_registered": sorted(set(gymnasium.registry) - gym_ids),
    "tasks_loaded": sorted([*registry.DEFAULT._loaded, *registry.DEFAULT._registered]),
    "tasks_scanned": registry.DEFAULT._scan_cache is not None,
    "mujoco_gl": os.environ.get("MUJOCO_GL"),
}))
"""


def _modules() -> list[str]:
    out = []
    for p in sorted(PACKAGE.rglob("*.py")):
        rel = p.relative_to(PACKAGE.parent).with_suffix("")
        if {"prompts", "mjcf"} & set(rel.parts) or rel.name == "__main__":  # templates; command lines
            continue
        out.append(".".join(rel.parts[:-1] if rel.name == "__init__" else rel.parts))
    return out


def _import_in_fresh_process(modules: list[str]) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    out = subprocess.run([sys.executable, "-c", _PROBE, json.dumps(modules)], env=env, capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_importing_every_capmj_module_sets_nothing_starts_nothing_registers_nothing() -> None:
    modules = [m for m in _modules() if m not in ALLOWED]
    assert len(modules) > 100 and "capmj.sim.cameras" in modules and "capmj.envs.gym_env" in modules
    got = _import_in_fresh_process(modules)
    assert got["failed"] == {}
    assert got["events"] == [], "processes started or environment written at import"
    assert got["env_changed"] == [] and got["mujoco_gl"] is None
    assert not got["sys_path_changed"] and got["signals_changed"] == []
    assert got["gym_registered"] == [] and got["tasks_loaded"] == [] and not got["tasks_scanned"]


def test_the_gymnasium_module_id_hook_registers_and_does_nothing_else() -> None:
    got = _import_in_fresh_process(["capmj.envs.gym_ids"])
    assert got["failed"] == {} and got["events"] == [] and got["env_changed"] == []
    assert "capmj/stack-all-blocks-on-a-zone-v0" in got["gym_registered"] and got["tasks_loaded"] == []
