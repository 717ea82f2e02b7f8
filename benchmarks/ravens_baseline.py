"""The PyBullet Ravens oracle, timed per pick-and-place: the baseline of ``benchmarks/primitives.py``.

Why: issue #17 compares capmj's pick-and-place speed with the original Ravens
(google-research/ravens) oracle, PyBullet with its EGL renderer on, run on the same machine.  The
Ravens figures in ``benchmarks/primitives.py`` (``RAVENS_EGL_*``) were quoted constants; this script
re-measures them so the side-by-side can be run again.

It runs ONLY in a separate venv with PyBullet and the few packages Ravens' environment and tasks
import (never in capmj's venv: Ravens and capmj are not installed together), from an unmodified
Ravens checkout given by ``--ravens-root``.  Nothing of Ravens is copied or edited; times are taken
by wrapping methods from outside:

Output ``per_action_s`` (seconds per oracle action, i.e. per pick-and-place):

- ``with_obs``: the whole ``env.step(action)`` (the PickPlace primitive, Ravens' wait until
  objects are static, reward and info, then ``_get_obs``: its three RealSense D415 RGB-D renders;
  PyBullet draws the segmentation mask in the same call);
- ``no_obs``: the same step minus the time inside ``env._get_obs``;
- ``primitive`` / ``obs_3_cameras`` / ``oracle_act``: the primitive alone, the three-camera
  observation alone, and the oracle's own action choice (one more render, of its top-down camera,
  plus heightmap reconstruction), which is outside ``env.step`` and in neither mode.

Episodes follow Ravens' ``demos.py``: ``np.random.seed(seed)``, ``env.set_task``, ``env.reset``,
then at most ``task.max_steps`` oracle actions; success is a total reward > 0.99, as there.  The
environment runs at ``--hz`` (480 in ``demos.py``; the ``Environment`` default is 240).

Deviation from a plain ``import ravens``: ``ravens/__init__.py`` imports the learning agents and so
TensorFlow; the package is registered here by its path without running that ``__init__`` (the
environment, the tasks and the utils modules are imported as they are).  Ravens' requirements.txt
pins gym 0.17.3 and numpy 1.18.5 (no Python 3.11 build of the latter); gym 0.26.2 and numpy 1.26.4
are used instead, for the same ``gym.Env`` / ``gym.spaces`` calls.  ``movej`` has a 5 s wall-clock timeout in Ravens: on a loaded
machine actions can time out (``movej_timeouts`` in the output).

Setup and run (see docs/speed.md):

    python3.11 -m venv /tmp/ravens-venv
    /tmp/ravens-venv/bin/pip install pybullet==3.2.7 numpy==1.26.4 gym==0.26.2 six scipy matplotlib \\
        meshcat transforms3d opencv-python-headless
    git clone https://github.com/google-research/ravens /tmp/ravens-src   # measured at 4752ffa
    /tmp/ravens-venv/bin/python benchmarks/ravens_baseline.py --ravens-root /tmp/ravens-src \\
        [--task stack-block-pyramid] [--episodes 10] [--seed 0] [--hz 480] [--no-egl]

Prints one JSON object on stdout; PyBullet's and Ravens' own prints go to stderr.
"""

from __future__ import annotations

import argparse
import ctypes
import importlib
import json
import os
import pkgutil
import re
import statistics
import subprocess
import sys
import tempfile
import time
import types
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, NoReturn

SETUP_HINT = (
    "run this in a separate venv with PyBullet and Ravens' dependencies, e.g.\n"
    "  python3.11 -m venv /tmp/ravens-venv\n"
    "  /tmp/ravens-venv/bin/pip install pybullet==3.2.7 numpy==1.26.4 gym==0.26.2 six scipy matplotlib meshcat "
    "transforms3d opencv-python-headless\n"
    "  git clone https://github.com/google-research/ravens /tmp/ravens-src\n"
    "  /tmp/ravens-venv/bin/python benchmarks/ravens_baseline.py --ravens-root /tmp/ravens-src\n"
    "(see docs/speed.md)"
)
DEFAULT_TASKS = ["place-red-in-green", "stack-block-pyramid"]


def die(msg: str) -> NoReturn:
    sys.exit(f"ravens_baseline: {msg}\n{SETUP_HINT}")


def import_ravens(root: str) -> tuple[Any, Any, Any, Any]:
    """(pybullet, ravens.tasks, Environment, PickPlace) from the checkout at ``root``.

    ``ravens`` is registered as a bare package on its directory so that ``ravens/__init__.py``
    (which imports the TensorFlow agents) does not run; the submodules are Ravens' own files.
    """
    try:
        import pybullet
    except ImportError as e:
        die(f"cannot import pybullet ({e})")
    pkg_dir = os.path.join(os.path.abspath(root), "ravens")
    if not os.path.isfile(os.path.join(pkg_dir, "environments", "environment.py")):
        die(f"--ravens-root {root!r} is not a Ravens checkout (no ravens/environments/environment.py)")
    pkg = types.ModuleType("ravens")
    pkg.__path__ = [pkg_dir]
    pkg.__file__ = os.path.join(pkg_dir, "__init__.py")
    sys.modules["ravens"] = pkg
    try:
        tasks = importlib.import_module("ravens.tasks")
        environment = importlib.import_module("ravens.environments.environment")
        primitives = importlib.import_module("ravens.tasks.primitives")
    except ImportError as e:
        die(f"cannot import Ravens' environment/tasks from {pkg_dir} ({e})")
    return pybullet, tasks, environment.Environment, primitives.PickPlace


def git_commit(root: str) -> str | None:
    try:
        out = subprocess.run(["git", "-C", root, "rev-parse", "HEAD"], capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        return None
    return out.stdout.strip() or None


@contextmanager
def native_stdout_to(path: str) -> Iterator[None]:
    """Sends fd 1 (PyBullet's C prints and Python's) to ``path``, so stdout carries only the JSON."""
    libc = ctypes.CDLL(None)
    sys.stdout.flush()
    libc.fflush(None)
    saved = os.dup(1)
    with open(path, "wb") as f:
        os.dup2(f.fileno(), 1)
    try:
        yield
    finally:
        sys.stdout.flush()
        libc.fflush(None)
        os.dup2(saved, 1)
        os.close(saved)


class Clock:
    """Accumulates the wall time spent inside a wrapped callable."""

    def __init__(self) -> None:
        self.seconds = 0.0
        self.calls = 0

    def wrap(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        perf = time.perf_counter

        def timed(*args: Any, **kwargs: Any) -> Any:
            t = perf()
            try:
                return fn(*args, **kwargs)
            finally:
                self.seconds += perf() - t
                self.calls += 1

        return timed


def stats(xs: list[float]) -> dict[str, float | int | None]:
    if not xs:
        return {"mean": None, "median": None, "min": None, "max": None, "count": 0}
    return {
        "mean": round(statistics.fmean(xs), 4),
        "median": round(statistics.median(xs), 4),
        "min": round(min(xs), 4),
        "max": round(max(xs), 4),
        "count": len(xs),
    }


def run_task(
    name: str, episodes: int, seed0: int, env: Any, tasks: Any, pick_place: Any, np: Any
) -> dict[str, Any]:
    task = tasks.names[name]()
    task.mode = "train"
    if not isinstance(task.primitive, pick_place):
        die(f"task {name!r} does not use the PickPlace primitive; pick a pick-and-place task")
    prim_clock, obs_clock = Clock(), Clock()
    task.primitive = prim_clock.wrap(task.primitive)  # env.step calls self.task.primitive(...)
    env._get_obs = obs_clock.wrap(env._get_obs)  # instance attribute shadows the method
    agent = task.oracle(env)
    per: dict[str, list[float]] = {"with_obs": [], "no_obs": [], "primitive": [], "obs_3_cameras": [], "oracle_act": []}
    reset_s: list[float] = []
    eps: list[dict[str, Any]] = []
    perf = time.perf_counter
    try:
        for k in range(episodes):
            seed = seed0 + k
            np.random.seed(seed)
            env.set_task(task)
            t = perf()
            obs = env.reset()
            reset_s.append(perf() - t)
            info: Any = None
            total, done, steps = 0.0, False, 0
            for _ in range(task.max_steps):
                t = perf()
                act = agent.act(obs, info)
                per["oracle_act"].append(perf() - t)
                if act is None:  # Ravens' oracle gives up when the object to pick is not visible
                    break
                p0, o0 = prim_clock.seconds, obs_clock.seconds
                t = perf()
                obs, reward, done, info = env.step(act)
                step_s = perf() - t
                obs_s = obs_clock.seconds - o0
                per["with_obs"].append(step_s)
                per["no_obs"].append(step_s - obs_s)
                per["primitive"].append(prim_clock.seconds - p0)
                per["obs_3_cameras"].append(obs_s)
                total += float(reward)
                steps += 1
                if done:
                    break
            eps.append({"seed": seed, "actions": steps, "total_reward": round(total, 3),
                        "done": bool(done), "success": total > 0.99})
    finally:
        del env._get_obs  # back to the class method for the next task
    return {
        "task": name,
        "episodes": episodes,
        "successes": sum(e["success"] for e in eps),
        "actions": sum(e["actions"] for e in eps),
        "per_action_s": {k: stats(v) for k, v in per.items()},
        "reset_s": stats(reset_s),
        "episode_results": eps,
        "_raw": per,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ravens-root", required=True, help="google-research/ravens checkout (the repo root)")
    ap.add_argument("--task", action="append", help=f"Ravens task name, repeatable (default {DEFAULT_TASKS})")
    ap.add_argument("--episodes", type=int, default=10, help="episodes per task")
    ap.add_argument("--seed", type=int, default=0, help="first seed; episode k uses seed + k")
    ap.add_argument("--hz", type=int, default=480, help="PyBullet steps per second (480 as in Ravens' demos.py)")
    ap.add_argument("--no-egl", action="store_true", help="PyBullet's CPU TinyRenderer instead of the EGL plugin")
    args = ap.parse_args()

    p, tasks, Environment, PickPlace = import_ravens(args.ravens_root)
    import numpy as np

    names = args.task or DEFAULT_TASKS
    unknown = [n for n in names if n not in tasks.names]
    if unknown:
        die(f"unknown task(s) {unknown}; Ravens has {sorted(tasks.names)}")
    assets = os.path.join(os.path.abspath(args.ravens_root), "ravens", "environments", "assets")
    egl_loader = pkgutil.get_loader("eglRenderer")

    log = tempfile.NamedTemporaryFile(prefix="ravens_baseline_", suffix=".log", delete=False)
    log.close()
    results: list[dict[str, Any]] = []
    t_all = time.perf_counter()
    try:
        with native_stdout_to(log.name):
            env = Environment(assets, disp=False, hz=args.hz, use_egl=not args.no_egl)
            plugin = env._egl_plugin
            for name in names:
                results.append(run_task(name, args.episodes, args.seed, env, tasks, PickPlace, np))
            env.close()
    finally:
        with open(log.name, errors="replace") as f:
            native = f.read()
        os.unlink(log.name)
        sys.stderr.write(native)
    wall = time.perf_counter() - t_all

    gl = dict(re.findall(r"^(GL_VENDOR|GL_RENDERER|GL_VERSION)=(.*)$", native, re.M))
    if args.no_egl:
        renderer = "TinyRenderer (CPU; EGL plugin not loaded)"
    elif plugin is not None and plugin >= 0:
        renderer = f"EGL plugin ({gl.get('GL_VENDOR', '?')}, {gl.get('GL_RENDERER', '?')})"
    else:
        renderer = "EGL requested but the plugin did not load: TinyRenderer (CPU)"
    pooled = {k: [x for r in results for x in r["_raw"][k]] for k in results[0]["_raw"]}
    for r in results:
        del r["_raw"]
    out = {
        "benchmark": "ravens_baseline",
        "tasks": names,
        "episodes_per_task": args.episodes,
        "seeds": [args.seed, args.seed + args.episodes - 1],
        "hz": args.hz,
        "renderer": renderer,
        "egl_plugin_id": plugin,
        "egl_plugin_file": egl_loader.get_filename() if egl_loader is not None else None,  # type: ignore[attr-defined]
        "gl": gl,
        "pybullet_version": _pybullet_version(),
        "pybullet_numpy": bool(p.isNumpyEnabled()),
        "numpy_version": np.__version__,
        "ravens_commit": git_commit(args.ravens_root),
        "python": sys.version.split()[0],
        "cpus": os.cpu_count(),
        "load_avg_1m": round(os.getloadavg()[0], 2),
        "wall_s": round(wall, 1),
        "movej_timeouts": native.count("movej exceeded"),
        "successes": sum(r["successes"] for r in results),
        "episodes": sum(r["episodes"] for r in results),
        "per_action_s": {k: stats(v) for k, v in pooled.items()},
        "per_task": results,
    }
    print(json.dumps(out))


def _pybullet_version() -> str | None:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("pybullet")
    except PackageNotFoundError:
        return None


if __name__ == "__main__":
    main()
