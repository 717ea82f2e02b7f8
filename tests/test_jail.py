"""The OS boundary around generated task code: the jail, its seccomp filter, the wire, the proxy.

Everything runs for real: ``bwrap`` jails, a jailed Python that installs its seccomp filter, JSON
frames over pipes, MuJoCo episodes in this process, a generated package installed with pip and
read back by the registry.  Each test states what the boundary promises and could fail if it did
not hold.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from capmj.confine import jail, wire
from capmj.confine.proxy import ConfinedTask, ModuleSource
from capmj.errors import ConfinedTaskError, ConfinementError
from capmj.sim.objects import ObjectSpec
from capmj.sim.state import SceneState
from capmj.tasks.protocol import Scene, make_scene
from generator_script import CANDIDATES
from hostile_candidates import MODULE, NAME

pytestmark = pytest.mark.jail

GOOD = (CANDIDATES / "good_zone_color.py").read_text()


def jailed_python(code: str, **env: str) -> subprocess.CompletedProcess[str]:
    """Run ``code`` in a jailed interpreter (the parent's environment extended by ``env``)."""
    full = {**os.environ, **env}
    return subprocess.run(jail.jail_command([sys.executable, "-I", "-c", textwrap.dedent(code)]), capture_output=True,
                          text=True, timeout=60, env=full)


# --------------------------------------------------------------------------------------- the jail
def test_jailed_code_writes_only_to_its_tmpfs_sees_no_key_and_runs_unprivileged(tmp_path):
    outside = tmp_path / "outside"
    r = jailed_python(f"""
        import json, os
        out = {{}}
        for p in ("/tmp/inside", {str(outside)!r}, "/usr/x", {str(Path(sys.prefix) / 'x')!r}, "/root/x"):
            try:
                open(p, "w").write("x")
                out[p] = "written"
            except OSError as e:
                out[p] = type(e).__name__
        status = dict(l.split(":", 1) for l in open("/proc/self/status").read().splitlines() if ":" in l)
        out["env"] = dict(os.environ)
        out["uid"] = os.getuid()
        out["caps"] = status["CapEff"].strip()
        out["pids"] = sorted(int(p) for p in os.listdir("/proc") if p.isdigit())
        out["home"] = os.path.exists({str(Path.home())!r}) and os.listdir({str(Path.home())!r})
        print(json.dumps(out))
    """, OPENAI_API_KEY="sk-planted-in-the-parent")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["/tmp/inside"] == "written"
    assert {out[p] for p in out if p.startswith("/") and p != "/tmp/inside"} <= {"OSError", "FileNotFoundError",
                                                                                "PermissionError"}
    assert not outside.exists()
    assert "OPENAI_API_KEY" not in out["env"] and set(out["env"]) <= set(jail.CLEAN_ENV) | {"PWD"}
    assert out["uid"] == jail.NOBODY and int(out["caps"], 16) == 0
    assert len(out["pids"]) <= 3  # its own PID namespace: bwrap's init, the interpreter
    home = Path.home()
    bound = {Path(p).relative_to(home).parts[0] for p in jail._readable_roots() if Path(p).is_relative_to(home)}
    assert set(out["home"] or []) <= bound  # of the home directory, only the interpreter's own folder


def test_seccomp_refuses_processes_programs_and_sockets_but_not_threads():
    r = jailed_python("""
        import json, os, socket, subprocess, threading
        from capmj.confine import seccomp
        seccomp.install()
        out = {}
        for name, f in (("fork", os.fork), ("exec", lambda: os.execv("/bin/true", ["true"])),
                        ("subprocess", lambda: subprocess.run(["true"])), ("socket", socket.socket)):
            try:
                f()
                out[name] = "allowed"
            except OSError as e:
                out[name] = e.errno
        t = threading.Thread(target=lambda: out.setdefault("thread", "ran"))
        t.start(); t.join()
        print(json.dumps(out))
    """)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out == {"fork": 1, "exec": 1, "subprocess": 1, "socket": 1, "thread": "ran"}  # 1: EPERM


def _descendants(root: int) -> list[int]:
    """Every living process below ``root`` (by parent pid, read from /proc)."""
    parent: dict[int, int] = {}
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except OSError:
            continue
        fields = stat.rsplit(")", 1)[1].split()
        if fields[0] != "Z":
            parent[int(pid)] = int(fields[1])
    found, frontier = [], [root]
    while frontier:
        kids = [p for p, pp in parent.items() if pp in frontier]
        found += kids
        frontier = kids
    return found


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_jailed_processes_are_gone_when_their_parent_is_killed(tmp_path):
    """kill -9 of the process holding a ConfinedTask: every process of its jail ends too."""
    parent = subprocess.Popen([sys.executable, "-c", textwrap.dedent(f"""
        import sys, time
        from capmj.confine.proxy import ConfinedTask, ModuleSource
        task = ConfinedTask(ModuleSource({MODULE!r}, {GOOD!r}))
        task.load()
        print(task.started, flush=True)
        time.sleep(600)
    """)], stdout=subprocess.PIPE, text=True)
    try:
        assert parent.stdout is not None
        assert int(parent.stdout.readline()) == 1  # one task process, forked by the jail's fork server
        jailed = _descendants(parent.pid)
        assert len(jailed) >= 4, jailed  # bwrap, its init, the fork server, the task process
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait(timeout=10)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and any(map(_alive, jailed)):
            time.sleep(0.1)
        assert [p for p in jailed if _alive(p)] == [], "jailed processes outlived their parent"
    finally:
        if parent.poll() is None:
            parent.kill()


# --------------------------------------------------------------------------------------- the wire
def _scene_dict(**change) -> dict:
    s = wire.scene_to_wire(Scene((ObjectSpec(1, "block", "red", (0.5, 0.0, 0.02), size="small"),), "Put it.", {"k": [1]}))
    s["objects"][0].update(change)
    return s


@pytest.mark.parametrize("change, words", [
    ({"color": "ultraviolet"}, "unknown colour"), ({"kind": "teleporter"}, "unknown kind"),
    ({"pos": [0.5, 0.0, 1e9]}, "finite number"), ({"pos": [0.5, 0.0]}, "expected 3 numbers"),
    ({"obj_id": 0}, "obj_id"), ({"size": "huge"}, "unknown size"), ({"scale": -1.0}, "scale"),
])
def test_the_wire_refuses_values_outside_the_world(change, words):
    with pytest.raises(wire.WireError, match=words):
        wire.scene_from_wire(_scene_dict(**change))


def test_the_wire_round_trips_records_and_refuses_non_json_and_huge_frames():
    scene = wire.scene_from_wire(_scene_dict())
    assert wire.scene_from_wire(wire.scene_to_wire(scene)) == scene
    state = SceneState.from_specs(scene.objects)
    assert wire.state_from_wire(wire.state_to_wire(state)).poses == state.poses
    rng = np.random.default_rng(7)
    rng.random(3)
    other = np.random.Generator(np.random.PCG64())
    other.bit_generator.state = wire.rng_from_wire(json.loads(json.dumps(wire.rng_to_wire(rng))))
    assert other.random() == rng.random()
    with pytest.raises(wire.WireError, match="not JSON"):
        wire.decode_frame(b'{"progress": NaN}')
    with pytest.raises(wire.WireError, match="exceeds the limit"):
        wire.frame_length((wire.MAX_FROM_JAIL + 1).to_bytes(4, "big"), wire.MAX_FROM_JAIL)
    with pytest.raises(wire.WireError, match="must be in"):
        wire.verdict_from_wire({"success": True, "progress": -0.5, "diagnostics": []})


# --------------------------------------------------------------------------------------- the proxy
def test_a_confined_task_gives_the_same_scenes_as_the_module_in_process():
    """Same seed, same scene, whether the module runs here (a trusted copy) or in the jail."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("good_zone_color_here", CANDIDATES / "good_zone_color.py")
    assert spec is not None and spec.loader is not None
    here = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(here)
    task = ConfinedTask(ModuleSource(MODULE, GOOD))
    try:
        for seed in (0, 5, 10001):
            assert make_scene(task, seed) == make_scene(here.TASK, seed)
        scene = make_scene(task, 3)
        assert task.oracle_goals(scene) == here.TASK.oracle_goals(scene)
        start = SceneState.from_specs(scene.objects)
        assert task.evaluate(scene, start) == here.TASK.evaluate(scene, start)
    finally:
        task.close()


SLEEPER = GOOD.replace("    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:\n",
                       "    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:\n"
                       "        _CALLS.append(1)\n"
                       "        if len(_CALLS) > 3:\n"
                       "            return Verdict(True, 1.0, ('lying after three calls',))\n") + "_CALLS: list = []\n"


def test_a_fresh_process_per_episode_keeps_a_call_counting_sleeper_asleep():
    from capmj.agents.oracle import OracleAgent  # noqa: F401 - the agents' import cost outside the timing
    from capmj.runner import run_episode
    from capmj.taskcheck import IdleAgent

    assert SLEEPER != GOOD
    task = ConfinedTask(ModuleSource(MODULE, SLEEPER))
    try:
        results = [run_episode(task, seed, IdleAgent()) for seed in range(4)]
        assert [r.success for r in results] == [False] * 4  # in one process it would lie from the 4th call
        assert task.started == 4
        # the same module kept in one process lies: what the fresh process prevents
        scene = make_scene(task, 0)
        verdicts = [task.evaluate(scene, SceneState.from_specs(scene.objects)).success for _ in range(5)]
        assert verdicts == [False, False, False, True, True]
    finally:
        task.close()


def test_the_tmpfs_is_emptied_between_episodes():
    """A sleeper that counts episodes in a file of its tmpfs finds its file gone at each new episode
    (the only way state could outlive a task process in the jail)."""
    counting = GOOD.replace("    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:\n",
                            "    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:\n"
                            "        _b = __builtins__ if isinstance(__builtins__, dict) else vars(__builtins__)\n"
                            "        with _b['open']('/tmp/episodes', 'a') as f:\n"
                            "            f.write('x')\n"
                            "        n = len(_b['open']('/tmp/episodes').read())\n"
                            "        return Verdict(n > 1, 0.0, (f'episodes seen: {n}',))\n")
    assert counting != GOOD
    task = ConfinedTask(ModuleSource(MODULE, counting), guard=False)  # the guard would refuse the write
    try:
        seen = []
        for seed in range(3):
            scene = make_scene(task, seed)
            seen.append(task.evaluate(scene, SceneState.from_specs(scene.objects)).diagnostics)
        assert seen == [("episodes seen: 1",)] * 3 and task.started == 3 and task.jails == 1
    finally:
        task.close()


def test_episodes_in_threads_get_their_own_task_processes_which_outlive_the_threads():
    """``--concurrency``: episodes run at once in threads; each thread gets its own jail, and a jail
    started from a thread survives the thread (bwrap dies with the thread that started it, so the
    jails are started from one long-lived launcher thread)."""
    import threading
    from concurrent.futures import ThreadPoolExecutor

    task = ConfinedTask(ModuleSource(MODULE, GOOD))
    together = threading.Barrier(3)

    def episode(seed: int) -> bool:
        together.wait(timeout=60)
        scene = make_scene(task, seed)
        return task.evaluate(scene, SceneState.from_specs(scene.objects)).success

    try:
        with ThreadPoolExecutor(3) as pool:
            assert list(pool.map(episode, range(3))) == [False] * 3
        assert task.jails == 3 and task.started == 3
        assert all(j.alive for j in task._live)  # the pool's threads are gone, their jails are not
    finally:
        task.close()
    assert task._live == []


def test_limits_and_failures_of_the_jailed_code_are_named():
    slow = GOOD.replace("        k = int(rng.integers(2, 4))", "        while True:\n            pass")
    task = ConfinedTask(ModuleSource(MODULE, slow), jail.Limits(cpu_s=2, wall_s=30))
    with pytest.raises(ConfinedTaskError, match="CPU-time limit of 2 s"):
        make_scene(task, 0)
    broken = ConfinedTask(ModuleSource(MODULE, GOOD.replace("TASK = ", "TASK_ = ")))
    with pytest.raises(ConfinedTaskError, match="defines no TASK"):
        broken.load()
    raising = GOOD.replace("        k = int(rng.integers(2, 4))", "        raise KeyError('no zone')")
    task = ConfinedTask(ModuleSource(MODULE, raising))
    with pytest.raises(ConfinedTaskError, match="KeyError: 'no zone'") as info:
        make_scene(task, 0)
    assert info.value.remote_type == "KeyError" and any("sample_scene" in n for n in info.value.__notes__)
    task.close()


# --------------------------------------------------------------------------------------- installed
@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """A generated package written by the generator's own writer from a real check run, pip-installed
    (not editable: pip compiles bytecode into __pycache__) into a target directory."""
    from generated_package import install_generated

    return install_generated(tmp_path_factory.mktemp("generated"))


def run_with(target: Path, code: str) -> dict:
    env = {**os.environ, "PYTHONPATH": str(target)}
    env.pop("CAPMJ_DISABLE_PLUGINS", None)
    r = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


COUNT_JAILS = """
    import json
    from capmj.confine import jail
    started = []
    _start = jail.start
    def counting(*a, **k):
        started.append(1)
        return _start(*a, **k)
    jail.start = counting
"""


def test_listing_an_installed_generated_task_runs_none_of_its_code(installed):
    out = run_with(installed, COUNT_JAILS + f"""
    from capmj.tasks import registry
    from capmj.generate.library import load_library
    names = [i.name for i in registry.list_tasks()]
    tags = sorted(registry.tags_of({NAME!r}))
    broken = list(registry.broken(load=True))
    picked = registry.resolve("generated-by-llm")
    lib = {{t.name: t.goal for t in load_library()}}
    listed = len(started)
    task = registry.get_task({NAME!r})
    import sys
    imported = [m for m in sys.modules if m.startswith("capmj_generated_jailtest")]
    from capmj.tasks.protocol import make_scene
    goal = make_scene(task, 10001).goal
    print(json.dumps({{"names": names, "tags": tags, "broken": broken, "picked": picked, "lib": lib.get({NAME!r}),
                      "listed": listed, "imported": imported, "goal": goal, "after_use": len(started),
                      "type": type(task).__name__}}))
    """)
    assert NAME in out["names"] and out["tags"] == ["generated-by-llm"] and out["picked"] == [NAME]
    assert out["broken"] == [] and out["lib"] == "Put every block in the zone of its color."
    assert out["listed"] == 0  # no jail started by listing, tags, resolving or the generator's library
    assert out["imported"] == [] and out["type"] == "ConfinedTask"  # never imported in capmj's process
    assert out["goal"] == "Put every block in the zone of its color." and out["after_use"] >= 1


def test_a_planted_pyc_or_a_changed_fact_is_refused_before_anything_runs(installed, tmp_path):
    import shutil

    copy = tmp_path / "site"
    shutil.copytree(installed, copy)
    pkg = copy / "capmj_generated_jailtest"
    assert (pkg / "__pycache__").is_dir()  # pip's bytecode: never read, so not refused
    (pkg / "put_blocks_in_zone_of_same_color.cpython-311.pyc").write_bytes(b"\0" * 16)
    out = run_with(copy, COUNT_JAILS + f"""
    from capmj.tasks import registry
    try:
        registry.get_task({NAME!r})
        print(json.dumps({{"error": None}}))
    except Exception as e:
        print(json.dumps({{"error": f"{{type(e).__name__}}: {{e}}", "started": len(started)}}))
    """)
    assert out["error"].startswith("ConfinementError") and "not in the manifest" in out["error"], out
    assert out["started"] == 0

    (pkg / "put_blocks_in_zone_of_same_color.cpython-311.pyc").unlink()
    manifest = json.loads((pkg / "capmj-confinement.json").read_text())
    manifest["tasks"][NAME]["facts"]["tags"] = ["benchmark"]  # a listing that says something else than the code
    (pkg / "capmj-confinement.json").write_text(json.dumps(manifest))
    out = run_with(copy, COUNT_JAILS + f"""
    from capmj.tasks import registry
    from capmj.tasks.protocol import make_scene
    task = registry.get_task({NAME!r})
    try:
        make_scene(task, 0)
        print(json.dumps({{"error": None}}))
    except Exception as e:
        print(json.dumps({{"error": f"{{type(e).__name__}}: {{e}}"}}))
    """)
    assert out["error"].startswith("ConfinementError") and "other facts than were accepted" in out["error"], out


def test_an_older_manifest_is_refused_with_the_fix(installed, tmp_path):
    import shutil

    from capmj.confine.manifest import verify

    copy = tmp_path / "pkg"
    shutil.copytree(installed / "capmj_generated_jailtest", copy)
    (copy / "capmj-confinement.json").write_text(json.dumps({"schema": 1, "modules": {}}))
    problems = verify(copy)
    assert len(problems) == 1 and "schema 1" in problems[0] and "generate it again" in problems[0]


def test_no_jail_is_a_clear_refusal(monkeypatch):
    jail.problem.cache_clear()
    monkeypatch.setattr(jail, "BWRAP", "bwrap-that-is-not-installed")
    try:
        with pytest.raises(ConfinementError, match="apt-get install bubblewrap"):
            ConfinedTask(ModuleSource(MODULE, GOOD)).load()
    finally:
        jail.problem.cache_clear()
