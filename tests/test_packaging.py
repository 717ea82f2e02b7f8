"""A built wheel works on its own: installed into a fresh virtualenv, run from outside the source tree.

The wheel must carry every prompt file (the planner's, the reference plans, the generator's) and
the world's MJCF (package data); an editable install cannot show that, because the source tree is
right there.  The virtualenv borrows the heavy dependencies from the running interpreter -- its
virtualenv or the system Python, whichever holds them (``tests/venvs.py``) -- and the wheel is
installed with ``--no-deps``, so the test needs no index beyond the wheel build itself.

Also here: every distribution the package and its tests import is declared in ``pyproject.toml``
(an undeclared one works in the developer's environment, where something else pulled it in, and
breaks for the user whose resolver did not).
"""

from __future__ import annotations

import ast
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from importlib.metadata import packages_distributions
from pathlib import Path

import pytest

from generator_script import GeneratorScript, candidate
from llm_stub_server import StubLLMServer
from venvs import make_venv

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ("pyproject.toml", "README.md", "src", "task_plugins", "prompts", "mjcf")
DATA = ("prompts", "mjcf")  # top-level folders shipped as capmj/<folder>/ package data
TASK, SEED = "stack-all-blocks-on-a-zone", 10001
GOOD, GOAL = "put-blocks-in-zone-of-same-color", "Put every block in the zone of its color."
DEMO_SIZE = ("32", "24")  # width, height: tiny images, the layout and determinism are what is tested

EPISODES = """
import json, sys
import capmj, capmj_tasks
from capmj.agents.oracle import OracleAgent
from capmj.agents.reference import ReferenceAgent, reference_plan
from capmj.generate.prompts import generator_dir
from capmj.resources import mjcf_path, prompts_dir
from capmj.runner import run_episode
from capmj.tasks.registry import get_task

task = get_task(sys.argv[1])
out = {"files": [capmj.__file__, capmj_tasks.__file__, reference_plan(task)[1], str(prompts_dir()),
                 str(generator_dir()), str(mjcf_path("table.xml"))]}
for agent in (ReferenceAgent(), OracleAgent()):
    r = run_episode(task, int(sys.argv[2]), agent)
    out[agent.name] = [r.success, r.error, r.primitives, r.sim_s]
print(json.dumps(out))
"""


def _build_isolated() -> bool:
    """Build with pip's build isolation unless this interpreter can already build the wheel."""
    try:
        import setuptools
        major = int(setuptools.__version__.split(".")[0])
        if major >= 71:  # bdist_wheel is part of setuptools from 70.1
            return False
        import wheel  # noqa: F401
        return major < 68
    except ImportError:
        return True


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    src = tmp_path_factory.mktemp("src")
    for name in SHIPPED:  # a clean copy: no build/ or egg-info in the checkout, no .venv in the sdist
        path = ROOT / name
        if path.is_dir():
            shutil.copytree(path, src / name, symlinks=True,
                            ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "build"))
        else:
            shutil.copy2(path, src / name)
    dist = tmp_path_factory.mktemp("dist")
    cmd = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(dist), str(src)]
    if not _build_isolated():
        cmd.insert(4, "--no-build-isolation")
    subprocess.run(cmd, check=True, cwd=src, timeout=300)
    (whl,) = dist.glob("capmj-*.whl")
    return whl


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory) -> tuple[Path, dict[str, str]]:
    """The python of a fresh virtualenv holding the wheel, and an environment that hides the source tree."""
    venv = tmp_path_factory.mktemp("wheel-venv") / "venv"
    py = make_venv(venv, own=[str(wheel)])
    drop = ("PYTHONPATH", "CAPMJ_PROMPTS_DIR", "CAPMJ_LLM_CACHE", "CAPMJ_DISABLE_PLUGINS")
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env["LITELLM_LOCAL_MODEL_COST_MAP"] = "True"  # no cost-map download at import
    where = subprocess.run([str(py), "-c", "import capmj; print(capmj.__file__)"], cwd=venv, env=env,
                           capture_output=True, text=True, timeout=120)
    assert Path(where.stdout.strip()).resolve().is_relative_to(venv.resolve()), where.stdout + where.stderr
    return py, env


def _run(py: Path, args: list[str], cwd: Path, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(py), *args], cwd=cwd, env=env, timeout=600, capture_output=True, text=True)


def test_wheel_ships_every_prompt_and_mjcf_file(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    for folder in DATA:
        files = [p for p in (ROOT / folder).rglob("*") if p.is_file() and "__pycache__" not in p.parts]
        assert files, folder
        missing = [str(p.relative_to(ROOT)) for p in files
                   if f"capmj/{folder}/{p.relative_to(ROOT / folder).as_posix()}" not in names]
        assert not missing, f"not in the wheel: {missing}"
    assert "capmj/prompts/generator/system.txt" in names and "capmj/mjcf/table.xml" in names
    assert not any(n.startswith(("capmj/prompts/", "capmj/mjcf/")) and n.endswith("__init__.py") for n in names)


PERCEIVERS = """
import json
from importlib.metadata import entry_points
from capmj.perception.plugins import load_perceiver, perception_modes, source_tree_entry_points

eps = [[e.name, e.value, e.dist.metadata["Name"]] for e in entry_points(group="capmj.perceivers")]
print(json.dumps({"eps": eps, "modes": list(perception_modes()), "rgbd": type(load_perceiver("rgbd")).__name__,
                  "source_tree": len(source_tree_entry_points())}))
"""


def test_wheel_declares_the_rgbd_perceiver_as_an_entry_point(wheel, installed, tmp_path):
    """capmj's own perceiver comes from its metadata, as a plugin's would: the wheel's
    entry_points.txt names it and importlib.metadata lists it where no source tree is at hand."""
    text = next(zipfile.ZipFile(wheel).read(n).decode() for n in zipfile.ZipFile(wheel).namelist()
                if n.endswith(".dist-info/entry_points.txt"))
    group = text.split("[capmj.perceivers]")[1].split("[")[0]
    assert "rgbd = capmj.perception.perceiver:ClassicalPerceiver" in group
    py, env = installed
    run = _run(py, ["-c", PERCEIVERS], tmp_path, env)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout.strip().splitlines()[-1])
    assert got["eps"] == [["rgbd", "capmj.perception.perceiver:ClassicalPerceiver", "capmj"]]
    assert got["modes"] == ["state", "rgbd"] and got["rgbd"] == "ClassicalPerceiver"
    assert got["source_tree"] == 0  # no pyproject beside the installed package: the metadata alone answered


def test_wheel_runs_reference_and_oracle_outside_the_source_tree(installed, tmp_path):
    py, env = installed
    run = _run(py, ["-c", EPISODES, TASK, str(SEED)], tmp_path, env)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout.strip().splitlines()[-1])
    site = (py.parent.parent / "lib").resolve()
    for f in got["files"]:  # the package, its tasks, a plan, the prompts and the MJCF all come from the wheel
        assert Path(f).resolve().is_relative_to(site), f
        assert not Path(f).resolve().is_relative_to(ROOT), f

    # ... and behave exactly as in the source tree.
    from capmj.agents.oracle import OracleAgent
    from capmj.agents.reference import ReferenceAgent
    from capmj.runner import run_episode
    from capmj.tasks.registry import get_task

    for agent in (ReferenceAgent(), OracleAgent()):
        r = run_episode(get_task(TASK), SEED, agent)
        assert got[agent.name] == [True, None, r.primitives, r.sim_s]


@pytest.mark.jail
def test_wheel_generates_a_task_with_its_packaged_prompts(installed, tmp_path):
    """``python -m capmj.generate`` against a scripted local server: every prompt it sends comes from the
    wheel's prompts/generator/ (the script recognises the task API text; a missing file is an error)."""
    py, env = installed
    out = tmp_path / "gen"
    with StubLLMServer(responder=GeneratorScript([candidate("good_zone_color.py", name=GOOD)])) as server:
        run = _run(py, ["-m", "capmj.generate", "--mode", "top-down", "--name", GOOD, "--description", GOAL,
                        "--model", "openai/stub", "--api-base", server.base_url, "--seeds", "1",
                        "--accept-rate", "1.0", "--package", "capmj-generated-wheel", "--out", str(out),
                        "--no-progress"], tmp_path, env)
        bodies = server.requests
    assert run.returncode == 0, run.stderr
    assert f"{GOOD}" in run.stdout and "1 of 1 accepted" in run.stdout, run.stdout
    line = json.loads((out / "generation.jsonl").read_text())
    assert line["stage"] == "accepted" and line["usage"]["calls"] == len(bodies) > 0, line
    # one system message for every request (a prefix cache reads it once): the wheel's system.txt
    # with the task API (task_api.txt) and the library filled in
    role = (ROOT / "prompts" / "generator" / "system.txt").read_text().split("$task_api")[0].strip()
    systems = {json.dumps(b["messages"][0]) for b in bodies}
    assert len(systems) == 1 and bodies[0]["messages"][0]["role"] == "system"
    content = bodies[0]["messages"][0]["content"]
    assert content.startswith(role) and "THE TASK API." in content and "$" not in content.split("EXISTING TASKS")[1]
    assert f'"{GOOD}" = "capmj_generated_wheel.' in (out / "pyproject.toml").read_text()


def _files(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def test_wheel_writes_demonstrations_identical_to_the_source_tree(installed, tmp_path):
    py, env = installed
    out = tmp_path / "demos"
    width, height = DEMO_SIZE
    run = _run(py, ["-m", "capmj.demos", "--tasks", TASK, "--split", "test", "--n", "1", "--out", str(out),
                    "--width", width, "--height", height, "--fast-robot", "--no-progress"], tmp_path, env)
    assert run.returncode == 0, run.stderr
    stats = json.loads(run.stdout.strip().splitlines()[-1])
    assert stats["task"] == TASK and stats["saved"] == 1 and stats["steps"] > 0, stats

    from capmj.demos.collect import collect_split
    from capmj.envs.tabletop import EnvConfig
    from capmj.sim.cameras import VIEW_CAMERAS

    here = tmp_path / "here"
    config = EnvConfig(cameras=VIEW_CAMERAS, width=int(width), height=int(height), robot_meshes=False)
    assert collect_split(TASK, "test", 1, here, config=config).saved == 1
    wheel_files, source_files = _files(out), _files(here)
    assert sorted(wheel_files) == sorted(source_files) and wheel_files == source_files


# ------------------------------------------------------------------------------ declared imports
IMPORTERS = ("src/capmj", "task_plugins/capmj_tasks", "tests")
NOT_IMPORTERS = ("prompts", "mjcf", "generator_candidates")  # LLM-facing text and deliberately bad candidates


def _requirement_name(req: str) -> str:
    match = re.match(r"[A-Za-z0-9][A-Za-z0-9._-]*", req.strip())
    assert match, req
    return re.sub(r"[-_.]+", "-", match.group(0)).lower()


def _declared() -> set[str]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    reqs = [*project["dependencies"], *(r for extra in project["optional-dependencies"].values() for r in extra)]
    return {_requirement_name(r) for r in reqs}


def _catches_import_error(node: ast.Try) -> bool:
    types = [h.type for h in node.handlers]
    names = {e.id for t in types for e in (t.elts if isinstance(t, ast.Tuple) else [t]) if isinstance(e, ast.Name)}
    return bool(names & {"ImportError", "ModuleNotFoundError"})


def _third_party_imports() -> dict[str, str]:
    """Top-level module -> a file importing it, for every absolute import that is not the standard
    library, not capmj's own and not a sibling test helper; imports in ``try: ... except ImportError``
    are optional by construction and left out."""
    own = {"capmj", "capmj_tasks", *(p.stem for p in (ROOT / "tests").glob("*.py"))}
    found: dict[str, str] = {}
    for folder in IMPORTERS:
        for path in sorted((ROOT / folder).rglob("*.py")):
            if any(part in NOT_IMPORTERS for part in path.relative_to(ROOT).parts):
                continue
            tree = ast.parse(path.read_text(), str(path))
            optional = {id(n) for t in ast.walk(tree) if isinstance(t, ast.Try) and _catches_import_error(t)
                        for stmt in t.body for n in ast.walk(stmt)}
            for node in ast.walk(tree):
                if id(node) in optional:
                    continue
                if isinstance(node, ast.Import):
                    modules = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    modules = [node.module]
                else:
                    continue
                for module in modules:
                    top = module.split(".")[0]
                    if top not in sys.stdlib_module_names and top not in own:
                        found.setdefault(top, str(path.relative_to(ROOT)))
    return found


def test_every_imported_distribution_is_declared():
    imports = _third_party_imports()
    assert {"mujoco", "numpy", "dm_env", "pytest"} <= set(imports)  # the scan sees what it must
    declared = _declared()
    providers = packages_distributions()
    undeclared = {}
    for module, where in imports.items():
        dists = {_requirement_name(d) for d in providers.get(module, [module])}  # not installed: its own name
        if not dists & declared:
            undeclared[module] = (sorted(dists), where)
    assert not undeclared, f"imported but not declared in pyproject.toml: {undeclared}"
