"""Tests of the task registry over the ``capmj.tasks`` entry-point group.

Third-party packages are really built and pip-installed: each is a source tree (pyproject + a
package) in a temp dir, installed with ``pip install --no-deps --no-build-isolation --no-index
--target <tmp>``.  The environment has no ``wheel`` package (setuptools < 70.1 needs it to build),
so the test packages use a tiny in-tree PEP 517 backend (``backend-path``) that writes the wheel;
pip does everything else (metadata, install, entry_points.txt).  Installing into a temp target
put on ``PYTHONPATH`` of a subprocess, rather than into site-packages, keeps the plugins (one of
them deliberately broken, one clashing) invisible to anything else running in this environment;
the targets are deleted afterwards.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from capmj.errors import ConfigError, PluginError
from capmj.sim.state import SceneState
from capmj.tasks import registry
from capmj.tasks.builtin import BENCHMARK_TASKS, GENERATED_TASKS
from capmj.tasks.protocol import Verdict, make_scene

BUILTIN = set(BENCHMARK_TASKS)
"""The ten benchmark tasks A–J (tag ``benchmark``)."""
CAPMJ_TASKS = {i.name for i in registry.list_tasks() if i.distribution == "capmj"}
"""Every task capmj itself declares: A–J and the extended tasks 1–10 (tag ``extended``)."""
CAPMJ_GENERATED = sorted(CAPMJ_TASKS - BUILTIN)

BACKEND = '''
"""Just enough of a PEP 517 backend to build a pure-Python wheel offline."""
import base64, hashlib, pathlib, tomllib, zipfile

def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    root = pathlib.Path.cwd()
    proj = tomllib.loads((root / "pyproject.toml").read_text())["project"]
    dist, version = proj["name"].replace("-", "_"), proj["version"]
    info = f"{dist}-{version}.dist-info"
    eps = "".join(f"[{g}]\\n" + "".join(f"{k} = {v}\\n" for k, v in e.items())
                  for g, e in proj.get("entry-points", {}).items())
    files = {p.relative_to(root).as_posix(): p.read_bytes() for d in sorted(root.iterdir())
             if (d / "__init__.py").is_file() for p in sorted(d.rglob("*.py"))}
    files[f"{info}/METADATA"] = f"Metadata-Version: 2.1\\nName: {proj['name']}\\nVersion: {version}\\n".encode()
    files[f"{info}/WHEEL"] = b"Wheel-Version: 1.0\\nGenerator: test\\nRoot-Is-Purelib: true\\nTag: py3-none-any\\n"
    files[f"{info}/entry_points.txt"] = eps.encode()
    record = "".join(f"{n},sha256={base64.urlsafe_b64encode(hashlib.sha256(b).digest()).rstrip(b'=').decode()},{len(b)}\\n"
                     for n, b in files.items()) + f"{info}/RECORD,,\\n"
    name = f"{dist}-{version}-py3-none-any.whl"
    with zipfile.ZipFile(pathlib.Path(wheel_directory) / name, "w") as z:
        for n, b in [*files.items(), (f"{info}/RECORD", record.encode())]:
            z.writestr(n, b)
    return name
'''

DEMO_MODULE = '''
"""capmj task plugin: put-block-in-zone."""

from __future__ import annotations

import numpy as np

from capmj.sim.state import SceneState
from capmj.tasks import predicates as P
from capmj.tasks.protocol import OracleGoal, Scene, Target, Verdict
from capmj.tasks.spawn import Spawner, pick_colors


class PutBlockInZone:
    """Put the one block into the zone.

    Task Description:
        "Put the {block color} block in the {zone color} zone."  One zone, one small block.

    Randomizations:
        Block and zone colours (distinct), both poses and yaws (collision-free).

    Success Conditions:
        The block's centre is inside the zone square (``predicates.in_zone``) and the block is
        not tilted more than 15 degrees.  Progress is 0 or 1.
    """

    def __init__(self, name: str = "put-block-in-zone", tags: frozenset[str] = frozenset({"demo"})) -> None:
        self.name, self.tags = name, tags

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        zone_color, block_color = pick_colors(rng, 2)
        sp = Spawner(rng)
        zone = sp.zone(zone_color)
        block = sp.block(block_color, "small")
        return Scene(sp.objects, f"Put the {block_color} block in the {zone_color} zone.",
                     {"zone": zone.obj_id, "block": block.obj_id})

    def oracle_goals(self, scene: Scene) -> list[OracleGoal]:
        zone, block = scene.by_id(scene.info["zone"]), scene.by_id(scene.info["block"])
        target = Target((float(zone.pos[0]), float(zone.pos[1]), block.height / 2))
        return [OracleGoal((block.obj_id,), (target,), ((1,),), metric="pose", tolerance=P.PLANE_TOL)]

    def evaluate(self, scene: Scene, state: SceneState) -> Verdict:
        block, zone = scene.info["block"], scene.info["zone"]
        label = P.short_label(state.spec(block))
        if P.toppled(state, block):
            return Verdict(False, 0.0, (f"{label} is tilted",))
        if not P.in_zone(state, block, zone):
            return Verdict(False, 0.0, (f"{label} is {P.zone_outside_distance(state, block, zone):.3f} m outside the zone",))
        return Verdict(True, 1.0, (f"{label} is in the zone",))


TASK = PutBlockInZone()


def make_generated() -> PutBlockInZone:
    """A zero-argument factory entry point."""
    return PutBlockInZone("put-block-in-zone-generated", frozenset({"demo", "generated"}))
'''

LEGACY_MODULE = DEMO_MODULE.replace("def sample_scene(", "def generate(").replace(
    'name: str = "put-block-in-zone"', 'name: str = "put-block-in-zone-legacy"')
"""The demo task as a plugin written before ``generate`` was renamed ``sample_scene`` (issue #28)."""
assert LEGACY_MODULE.count("def generate(") == 1 and "def sample_scene(" not in LEGACY_MODULE

BOTH_MODULE = '''
from legacy_tasks.zone import PutBlockInZone


class HalfMigrated(PutBlockInZone):
    __doc__ = PutBlockInZone.__doc__

    def sample_scene(self, rng):
        return super().generate(rng)


TASK = HalfMigrated("put-block-in-zone-both")
'''
"""A plugin half way through the rename: both names, as different methods."""

PACKAGES: dict[str, tuple[str, str, dict[str, str], dict[str, str]]] = {
    # key: (distribution, version, entry points, {module path: source})
    "demo": ("capmj-demo-tasks", "0.3.1",
             {"put-block-in-zone": "demo_tasks.zone:TASK",
              "put-block-in-zone-generated": "demo_tasks.zone:make_generated"},
             {"demo_tasks/zone.py": DEMO_MODULE}),
    "broken": ("capmj-broken-tasks", "2.0.0",
               {"exploding-task": "broken_tasks.boom:TASK", "misnamed-task": "broken_tasks.bad:TASK"},
               {"broken_tasks/boom.py": 'raise ImportError("needs libfoo, which is not installed")\n',
                "broken_tasks/bad.py": "class Bad:\n    name = 'other-name'\n    tags = frozenset()\n"
                                       "    def sample_scene(self, rng): ...\n\nTASK = Bad()\n"}),
    "dup": ("capmj-dup-tasks", "1.0.0", {"stack-all-blocks-on-a-zone": "dup_tasks.clone:TASK"},
            {"dup_tasks/clone.py": "TASK = None\n"}),
    "legacy": ("capmj-legacy-tasks", "0.2.0",
               {"put-block-in-zone-legacy": "legacy_tasks.zone:TASK", "put-block-in-zone-both": "legacy_tasks.both:TASK"},
               {"legacy_tasks/zone.py": LEGACY_MODULE, "legacy_tasks/both.py": BOTH_MODULE}),
}


def _install(root: Path, key: str) -> Path:
    """Write the source tree of package ``key`` and pip-install it into its own target dir."""
    dist, version, eps, modules = PACKAGES[key]
    src, target = root / f"{key}-src", root / f"{key}-site"
    (src / "_backend").mkdir(parents=True)
    (src / "_backend" / "mini_backend.py").write_text(BACKEND)
    entry_lines = "".join(f'"{k}" = "{v}"\n' for k, v in eps.items())
    (src / "pyproject.toml").write_text(
        '[build-system]\nrequires = []\nbuild-backend = "mini_backend"\nbackend-path = ["_backend"]\n\n'
        f'[project]\nname = "{dist}"\nversion = "{version}"\n\n[project.entry-points."capmj.tasks"]\n{entry_lines}')
    for rel, text in modules.items():
        (src / rel).parent.mkdir(parents=True, exist_ok=True)
        (src / rel).parent.joinpath("__init__.py").touch()
        (src / rel).write_text(textwrap.dedent(text))
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--no-deps",
                        "--no-build-isolation", "--no-index", "--target", str(target), str(src)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    return target


@pytest.fixture(scope="module")
def sites(tmp_path_factory):
    root = tmp_path_factory.mktemp("plugins")
    try:
        yield {key: _install(root, key) for key in PACKAGES}
    finally:
        shutil.rmtree(root, ignore_errors=True)


def run(code: str, *paths: Path, disable: bool = False) -> dict:
    """Run ``code`` in a fresh interpreter with ``paths`` on PYTHONPATH; it prints one JSON value."""
    env = {k: v for k, v in os.environ.items() if k != registry.DISABLE_ENV}
    if disable:
        env[registry.DISABLE_ENV] = "1"
    env["PYTHONPATH"] = os.pathsep.join([*map(str, paths), env.get("PYTHONPATH", "")]).strip(os.pathsep)
    r = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, capture_output=True,
                       text=True, timeout=120, cwd=paths[0] if paths else None)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


@pytest.fixture(autouse=True)
def fresh_registry(monkeypatch):
    monkeypatch.delenv(registry.DISABLE_ENV, raising=False)
    registry.reset()
    yield
    registry.reset()


# --------------------------------------------------------------------------------------- built-ins
def test_builtin_tasks_listed_from_capmj_with_benchmark_or_extended_tag():
    infos = {i.name: i for i in registry.list_tasks()}
    assert set(infos) == CAPMJ_TASKS and BUILTIN < CAPMJ_TASKS
    for name, info in infos.items():
        assert info.distribution == "capmj" and info.version
        assert info.value.startswith("capmj_tasks.") and info.value.endswith(":TASK")
        assert registry.tags_of(name) == ({"benchmark"} if name in BUILTIN else {"extended"})
    assert registry.resolve("benchmark") == sorted(BUILTIN)
    assert registry.resolve("extended") == CAPMJ_GENERATED == sorted(GENERATED_TASKS)
    with pytest.warns(FutureWarning, match="'generated' is now 'extended'"):  # the old name still selects them
        assert registry.resolve("generated") == CAPMJ_GENERATED
    assert registry.broken(load=True) == {}


def test_listing_imports_no_plugin_module():
    out = run("""
        import json, sys
        from capmj.tasks.registry import list_tasks
        names = [i.name for i in list_tasks()]
        print(json.dumps({"n": len(names), "mods": [m for m in sys.modules if m.startswith("capmj_tasks")]}))
    """)
    assert out == {"n": len(CAPMJ_TASKS), "mods": []}


def test_get_task_returns_a_working_cached_task():
    task = registry.get_task("stack-all-blocks-on-a-zone")
    assert registry.get_task("stack-all-blocks-on-a-zone") is task
    scene = make_scene(task, 0)
    verdict = task.evaluate(scene, SceneState.from_specs(scene.objects))
    assert isinstance(verdict, Verdict) and not verdict.success


def test_unknown_names_raise_config_error_with_suggestions():
    with pytest.raises(ConfigError, match="did you mean 'stack-all-blocks-on-a-zone'") as e:
        registry.get_task("stack-all-block-on-a-zone")
    assert "put-block-into-matching-bowl" in str(e.value)
    with pytest.raises(ConfigError, match=r"'benchmrk'.*did you mean 'benchmark'.*valid tags: benchmark"):
        registry.resolve("stack-blocks-of-same-size, benchmrk")
    with pytest.raises(ConfigError, match="empty"):
        registry.resolve(" , ")


def test_resolve_keeps_order_drops_repeats_and_expands_all():
    assert registry.resolve(["stack-blocks-of-same-size", "put-block-into-matching-bowl,stack-blocks-of-same-size"]) == [
        "stack-blocks-of-same-size", "put-block-into-matching-bowl"]
    got = registry.resolve("put-block-into-matching-bowl,all")
    assert got[0] == "put-block-into-matching-bowl" and sorted(got) == sorted(CAPMJ_TASKS)


def test_register_validates_and_works_with_plugins_disabled(monkeypatch):
    monkeypatch.setenv(registry.DISABLE_ENV, "1")
    assert registry.list_tasks() == []
    with pytest.raises(ConfigError, match="disabled"):
        registry.get_task("stack-all-blocks-on-a-zone")
    ns: dict = {}
    exec(compile(textwrap.dedent(DEMO_MODULE), "demo", "exec"), ns)
    task = registry.register(ns["make_generated"]())
    assert [i.name for i in registry.list_tasks()] == ["put-block-in-zone-generated"]
    assert registry.list_tasks()[0].distribution == registry.REGISTERED
    assert registry.get_task("put-block-in-zone-generated") is task
    assert registry.resolve("generated") == ["put-block-in-zone-generated"]
    with pytest.raises(PluginError, match="already exists"):
        registry.register(ns["make_generated"]())
    undocumented = type("Undocumented", (), {"name": "x", "tags": frozenset(), "sample_scene": len,
                                             "oracle_goals": len, "evaluate": len})()
    with pytest.raises(PluginError, match="Task Description:, Randomizations:, Success Conditions:"):
        registry.register(undocumented)


# --------------------------------------------------------------------------------------- third party
def test_third_party_package_runs_through_the_registry(sites):
    out = run("""
        import json
        from capmj.sim.state import Pose, SceneState
        from capmj.tasks import predicates as P, registry
        from capmj.tasks.protocol import make_scene
        infos = {i.name: [i.distribution, i.version, i.value] for i in registry.list_tasks()}
        task = registry.get_task("put-block-in-zone")
        scene = make_scene(task, 7)
        start = task.evaluate(scene, SceneState.from_specs(scene.objects))
        goal = task.oracle_goals(scene)[0]
        poses = dict(SceneState.from_specs(scene.objects).poses)
        poses[goal.objects[0]] = Pose(goal.targets[0].pos)
        solved = SceneState(scene.objects, poses)
        end = task.evaluate(scene, solved)
        print(json.dumps({"info": infos["put-block-in-zone"], "n": len(infos), "goal": scene.goal,
                          "start": start.success, "end": end.success, "reward": P.ravens_reward([goal], solved),
                          "demo": registry.resolve("demo"), "generated": registry.resolve("generated"),
                          "factory_tags": sorted(registry.tags_of("put-block-in-zone-generated"))}))
    """, sites["demo"])
    assert out["info"] == ["capmj-demo-tasks", "0.3.1", "demo_tasks.zone:TASK"]
    assert out["n"] == len(CAPMJ_TASKS) + 2 and out["goal"].startswith("Put the ")
    assert (out["start"], out["end"], out["reward"]) == (False, True, 1.0)
    assert out["demo"] == ["put-block-in-zone", "put-block-in-zone-generated"]
    assert out["generated"] == sorted(CAPMJ_GENERATED + ["put-block-in-zone-generated"])
    assert out["factory_tags"] == ["demo", "generated"]


def test_plugin_written_before_the_rename_loads_and_runs_with_one_warning(sites):
    """A third-party package whose task defines only ``generate``: the same scenes as the renamed
    demo task, an oracle episode it solves, one DeprecationWarning naming the new method and
    pointing at the plugin's file; a task defining both names differently is a PluginError."""
    out = run("""
        import json, warnings
        from capmj.agents.oracle import OracleAgent
        from capmj.errors import PluginError, TaskError
        from capmj.runner import run_episode
        from capmj.tasks import registry
        from capmj.tasks.protocol import make_scene
        legacy, demo = registry.get_task("put-block-in-zone-legacy"), registry.get_task("put-block-in-zone")
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            same = [make_scene(legacy, s) == make_scene(demo, s) for s in (7, 8, 9)]
            episode = run_episode(legacy, 10001, OracleAgent())
        deps = [w for w in got if issubclass(w.category, DeprecationWarning)]
        try:
            registry.get_task("put-block-in-zone-both")
            both = None
        except PluginError as e:
            both = {"text": str(e), "task_error": isinstance(e, TaskError)}
        print(json.dumps({"same": same, "success": episode.success, "error": episode.error,
                          "warnings": [[str(w.message), w.filename] for w in deps], "both": both,
                          "broken": sorted(registry.broken())}))
    """, sites["legacy"], sites["demo"])
    assert out["same"] == [True, True, True]
    assert (out["success"], out["error"]) == (True, None)
    [(message, filename)] = out["warnings"]
    assert "PutBlockInZone defines 'generate(rng)'" in message and "rename it to 'sample_scene(rng)'" in message
    assert filename.endswith(os.path.join("legacy_tasks", "zone.py"))
    both = out["both"]
    assert both is not None and both["task_error"] and "capmj-legacy-tasks 0.2.0" in both["text"]
    assert "both 'sample_scene' and 'generate'" in both["text"] and out["broken"] == ["put-block-in-zone-both"]


def test_broken_plugin_is_reported_and_others_still_work(sites):
    out = run("""
        import json
        from capmj.errors import PluginError
        from capmj.tasks import registry
        listed = [i.name for i in registry.list_tasks()]
        errors = {}
        for name in ("exploding-task", "misnamed-task"):
            try:
                registry.get_task(name)
            except PluginError as e:
                errors[name] = str(e)
        bench = registry.resolve("benchmark,demo")
        print(json.dumps({"listed": listed, "errors": errors, "bench": bench, "broken": sorted(registry.broken()),
                          "ok": registry.get_task("put-block-in-zone").name}))
    """, sites["broken"], sites["demo"])
    assert {"exploding-task", "misnamed-task"} <= set(out["listed"])
    boom = out["errors"]["exploding-task"]
    assert "capmj-broken-tasks 2.0.0" in boom and "ImportError: needs libfoo, which is not installed" in boom
    bad = out["errors"]["misnamed-task"]
    assert "capmj-broken-tasks 2.0.0" in bad and "'other-name'" in bad and "'evaluate' is missing" in bad
    assert out["bench"] == sorted(BUILTIN) + ["put-block-in-zone", "put-block-in-zone-generated"]
    assert out["broken"] == ["exploding-task", "misnamed-task"] and out["ok"] == "put-block-in-zone"


def test_duplicate_name_is_reported_naming_both_distributions(sites):
    out = run("""
        import json
        from capmj.errors import PluginError
        from capmj.tasks import registry
        try:
            registry.get_task("stack-all-blocks-on-a-zone")
            err = None
        except PluginError as e:
            err = str(e)
        print(json.dumps({"err": err, "listed": [i.name for i in registry.list_tasks()],
                          "broken": sorted(registry.broken()), "all": registry.resolve("all"),
                          "other": registry.get_task("stack-blocks-of-same-size").name}))
    """, sites["dup"])
    assert "capmj 0.1.0" in out["err"] and "capmj-dup-tasks 1.0.0" in out["err"]
    assert "stack-all-blocks-on-a-zone" not in out["listed"] and len(out["listed"]) == len(CAPMJ_TASKS) - 1
    assert out["broken"] == ["stack-all-blocks-on-a-zone"] and len(out["all"]) == len(CAPMJ_TASKS) - 1
    assert out["other"] == "stack-blocks-of-same-size"


def test_disable_plugins_hides_entry_points(sites):
    out = run("""
        import json
        from capmj.errors import ConfigError
        from capmj.tasks import registry
        try:
            registry.get_task("put-block-in-zone")
            err = None
        except ConfigError as e:
            err = str(e)
        print(json.dumps({"listed": registry.list_tasks(), "err": err}))
    """, sites["demo"], disable=True)
    assert out["listed"] == [] and "unknown task 'put-block-in-zone'" in out["err"]
