"""A built wheel works on its own: installed into a fresh virtualenv, run from outside the source tree.

The wheel must carry the prompt files and the world's MJCF (package data); an editable install
cannot show that, because the source tree is right there.  The virtualenv borrows the heavy
dependencies from the interpreter's site-packages (``--system-site-packages``) and the wheel is
installed with ``--no-deps``, so the test needs no index beyond the wheel build itself.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ("pyproject.toml", "README.md", "src", "task_plugins", "prompts", "mjcf")
TASK, SEED = "stack-all-blocks-on-a-zone", 10001

EPISODES = """
import json, sys
import capmj, capmj_tasks
from capmj.agents.oracle import OracleAgent
from capmj.agents.reference import ReferenceAgent, reference_plan
from capmj.resources import mjcf_path, prompts_dir
from capmj.runner import run_episode
from capmj.tasks.registry import get_task

task = get_task(sys.argv[1])
out = {"files": [capmj.__file__, capmj_tasks.__file__, reference_plan(task)[1], str(prompts_dir()),
                 str(mjcf_path("table.xml"))]}
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


def test_wheel_runs_reference_and_oracle_outside_the_source_tree(wheel, tmp_path):
    import zipfile

    names = set(zipfile.ZipFile(wheel).namelist())
    assert f"capmj/prompts/reference/{TASK}.py" in names and "capmj/prompts/system.txt" in names
    assert "capmj/mjcf/table.xml" in names and "capmj/mjcf/fixture.xml" in names
    assert not any(n.startswith("capmj/prompts/") and n.endswith("__init__.py") for n in names)

    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True, timeout=120)
    py = venv / "bin" / "python"
    subprocess.run([str(py), "-m", "pip", "install", "-q", "--no-deps", "--no-index", str(wheel)],
                   check=True, timeout=300)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "CAPMJ_PROMPTS_DIR")}
    env.update(PYTHONNOUSERSITE="1", LITELLM_LOCAL_MODEL_COST_MAP="True")
    run = subprocess.run([str(py), "-c", EPISODES, TASK, str(SEED)], cwd=tmp_path, env=env, timeout=300,
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout.strip().splitlines()[-1])
    site = (venv / "lib").resolve()
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
