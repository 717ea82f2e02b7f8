"""Install the good candidate two ways, for tests and ``benchmarks/confinement.py``: as a generated
package (the generator's own writer, after a real jailed check run) and as a trusted plugin with
the same module text (no manifest, not tagged as LLM-written: capmj imports it in-process).

Both go in with ``pip install --target`` (not editable: pip compiles bytecode, as a user's
install does), so a process with the target on ``PYTHONPATH`` finds the task through the
``capmj.tasks`` entry points.  Fixtures, never results.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from generator_script import CANDIDATES
from hostile_candidates import NAME

GOOD = (CANDIDATES / "good_zone_color.py").read_text()
GOAL = "Put every block in the zone of its color."
PACKAGE = "capmj-generated-jailtest"


def _pip_target(src: Path, target: Path) -> Path:
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--no-deps",
                        "--no-build-isolation", "--no-index", "--target", str(target), str(src)],
                       capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        raise RuntimeError(r.stdout + r.stderr)
    return target


def install_generated(root: Path) -> Path:
    """Check the good candidate in the jail, write its package as the generator does, install it;
    returns the target directory."""
    from capmj.confine.jail import Limits
    from capmj.confine.proxy import ModuleSource
    from capmj.generate.candidate import CandidateRecord
    from capmj.generate.config import GenerateConfig
    from capmj.generate.isolate import run_isolated
    from capmj.generate.package import write_package

    cfg = GenerateConfig(mode="top-down", model="openai/none", out=root / "generated-src", name=NAME,
                         description=GOAL, package=PACKAGE)
    source = ModuleSource(cfg.module_of(NAME), GOOD)
    run = run_isolated(source, name=NAME, seeds=(0,), accept_rate=1.0, tags=("generated-by-llm",),
                       limits=Limits(wall_s=120))
    if not all(r.passed for r in run.results):
        raise RuntimeError(f"the good candidate failed its checks: {run.results}")
    rec = CandidateRecord(0, "top-down", stage="accepted", accepted=True, name=NAME, goals=[GOAL],
                          confinement={"sha256": source.sha256, "jail": run.jail}, facts=run.facts, text=GOOD)
    cfg.out.mkdir(parents=True)
    write_package(cfg, [rec])
    return _pip_target(cfg.out, root / "generated-site")


def install_trusted_copy(root: Path) -> Path:
    """The same module as an ordinary plugin package (what a person would publish)."""
    src = root / "trusted-src"
    (src / "capmj_trusted_copy").mkdir(parents=True)
    (src / "capmj_trusted_copy" / "__init__.py").write_text("")
    (src / "capmj_trusted_copy" / "zone_color.py").write_text(GOOD)
    (src / "pyproject.toml").write_text(
        '[build-system]\nrequires = ["setuptools>=64"]\nbuild-backend = "setuptools.build_meta"\n\n'
        '[project]\nname = "capmj-trusted-copy"\nversion = "0.1.0"\n\n'
        f'[project.entry-points."capmj.tasks"]\n"{NAME}" = "capmj_trusted_copy.zone_color:TASK"\n\n'
        '[tool.setuptools]\npackages = ["capmj_trusted_copy"]\n')
    return _pip_target(src, root / "trusted-site")


__all__ = ["GOAL", "GOOD", "PACKAGE", "install_generated", "install_trusted_copy"]
