"""Write the accepted tasks as an installable plugin package, and ``generation.jsonl``.

Layout of ``--out DIR``::

    DIR/pyproject.toml            capmj.tasks entry points, keyword generated-by-llm
    DIR/<import_name>/*.py        one module per accepted task: the exact text its checks ran on
    DIR/<import_name>/capmj-confinement.json   every file's sha256, each task's facts and how it was confined
    DIR/README.md                 each task's goal and check results; every rejected candidate
    DIR/tests/test_generated_tasks.py   re-runs the runtime checks (pytest)
    DIR/generation.jsonl          one line per candidate
    DIR/candidates/, DIR/conversations/   every candidate's code and full conversation

Everything but ``generation.jsonl`` and the conversation logs (which carry timings and cache
flags) is a pure function of the candidates, so a rerun from the LLM cache writes the same
package byte for byte.
"""

from __future__ import annotations

import json
from typing import Sequence

from capmj.generate.candidate import CandidateRecord
from capmj.confine.manifest import MANIFEST, manifest_text
from capmj.generate.config import GENERATED_TAG, GenerateConfig, module_name

TEST_FILE = "tests/test_generated_tasks.py"

_TEST = '''"""Re-run the runtime checks of the generated tasks (python -m pytest {test_file})."""

import pytest

from capmj.taskcheck import CheckConfig, check_task
from capmj.tasks.registry import get_task

TASKS = {names!r}
SEEDS = {seeds}
ACCEPT_RATE = {rate!r}


@pytest.mark.parametrize("name", TASKS)
def test_runtime_checks(name):
    cfg = CheckConfig.first(SEEDS, accept_rate=ACCEPT_RATE, name=name, required_tags=frozenset({{"{tag}"}}))
    report = check_task(get_task(name), cfg)
    assert report.passed, report.text()
'''


def _pyproject(cfg: GenerateConfig, tasks: Sequence[CandidateRecord]) -> str:
    eps = "".join(f'"{r.name}" = "{cfg.import_name}.{module_name(r.name or "")}:TASK"\n' for r in tasks)
    return (
        '[build-system]\nrequires = ["setuptools>=64", "wheel"]\nbuild-backend = "setuptools.build_meta"\n\n'
        f'[project]\nname = "{cfg.package}"\nversion = "0.1.0"\n'
        f'description = "capmj tasks written by an LLM ({cfg.model}) and accepted by physics checks"\n'
        f'keywords = ["capmj", "{GENERATED_TAG}"]\nrequires-python = ">=3.11"\ndependencies = ["capmj"]\n\n'
        f'[project.entry-points."capmj.tasks"]\n{eps}\n'
        f'[tool.setuptools]\npackages = ["{cfg.import_name}"]\n\n'
        f'[tool.setuptools.package-data]\n{cfg.import_name} = ["{MANIFEST}"]\n')


def _check_table(rec: CandidateRecord) -> list[str]:
    last = max((c["attempt"] for c in rec.checks), default=1)
    rows = ["| check | outcome | detail |", "|---|---|---|"]
    for c in rec.checks:
        if c["attempt"] == last:
            rows.append(f"| {c['name']} | {c['outcome']} | {c['detail'].replace('|', '/')} |")
    return rows


def _readme(cfg: GenerateConfig, records: Sequence[CandidateRecord]) -> str:
    acc = [r for r in records if r.accepted]
    lines = [f"# {cfg.package}", "",
             f"capmj tasks written by `{cfg.model}` with `python -m capmj.generate --mode {cfg.mode}` and accepted "
             f"only after physics checks: oracle success on >= {cfg.accept_rate:g} of {cfg.seeds} distinct seeds, "
             "deterministic scenes, goal text naming only present objects, not solved at reset, a do-nothing "
             "episode failing, and the Ravens reward agreeing with the predicate.", "",
             "```", "pip install -e .            # the tasks appear in python -m capmj.bench --list",
             f"python -m capmj.bench --tasks {GENERATED_TAG} --seeds 10001:10011:2",
             f"python -m pytest {TEST_FILE}   # re-run the runtime checks", "```", "",
             f"{len(acc)} of {len(records)} candidates accepted.", "",
             "## How the code was confined", "",
             "Each module is LLM-written code, and capmj never imports it. Before anything of it ran, a static "
             "check allowed only the names of the documented task API (`capmj.confine.allowlist`). Its checks then "
             "ran with the code in a jail (bubblewrap: its own user, PID, mount, network and IPC namespaces, a "
             "read-only root, no capabilities, no environment, a seccomp filter against new processes and programs, "
             "CPU, memory and wall-time limits); capmj computed every check from the scenes, goals and verdicts "
             "the jailed task returned, with a fresh jailed process per episode. "
             f"`{cfg.import_name}/{MANIFEST}` records the sha256 of every file and what each task stated; capmj "
             "re-checks both before it uses a task from this package, and then runs it in the same jail "
             "(`python -m capmj.tasks check NAME` shows the checks).", ""]
    for r in acc:
        lines += [f"## {r.name}", "", f"Goal, e.g.: {' / '.join(repr(g) for g in r.goals[:3])}", "",
                  f"Module: `{cfg.import_name}/{module_name(r.name or '')}.py`; examples it learnt from: "
                  f"{', '.join(r.examples)}; repaired: {'yes' if r.repaired else 'no'}; reflection: "
                  f"{(r.reflection or {}).get('vote')} ({(r.reflection or {}).get('reason', '')})", "",
                  *_check_table(r), ""]
    rejected = [r for r in records if not r.accepted]
    if rejected:
        lines += ["## Rejected candidates", "", "| # | name | stage | reason |", "|---|---|---|---|"]
        lines += [f"| {r.index} | {r.name} | {r.stage} | {r.reason.replace('|', '/')[:300]} |" for r in rejected]
        lines.append("")
    return "\n".join(lines)


JOURNAL = "generation.jsonl"
"""One JSON line per candidate: appended as each finishes, rewritten in index order at the end."""


def write_package(cfg: GenerateConfig, records: Sequence[CandidateRecord]) -> list[CandidateRecord]:
    """Write the package of the accepted records (if any), the README and generation.jsonl.

    Returns the tasks in the package.
    """
    out = cfg.out
    acc = [r for r in records if r.accepted]
    if acc:
        pkg = out / cfg.import_name
        pkg.mkdir(parents=True, exist_ok=True)
        files = {"__init__.py": f'"""Tasks generated by capmj.generate: {", ".join(r.name or "" for r in acc)}."""\n'}
        tasks = {}
        for r in acc:  # the exact texts the checks ran on, never a file the checks could have touched
            rel = f"{module_name(r.name or '')}.py"
            if r.text is None:
                raise ValueError(f"accepted candidate {r.index} carries no checked text to package")
            files[rel] = r.text
            tasks[r.name or ""] = {"module": rel, "facts": r.facts, "goal": r.goals[0] if r.goals else "",
                                   "confinement": r.confinement}
        for rel, text in files.items():
            (pkg / rel).write_text(text, encoding="utf-8")
        (pkg / MANIFEST).write_text(manifest_text(cfg.import_name, files, tasks), encoding="utf-8")
        (out / "pyproject.toml").write_text(_pyproject(cfg, acc), encoding="utf-8")
        test = out / TEST_FILE
        test.parent.mkdir(parents=True, exist_ok=True)
        test.write_text(_TEST.format(test_file=TEST_FILE, names=[r.name for r in acc], seeds=cfg.seeds,
                                     rate=cfg.accept_rate, tag=GENERATED_TAG), encoding="utf-8")
    (out / "README.md").write_text(_readme(cfg, records), encoding="utf-8")
    with open(out / JOURNAL, "w", encoding="utf-8") as f:
        for r in records:
            f.write(json.dumps(r.to_dict()) + "\n")
    return acc


__all__ = ["JOURNAL", "TEST_FILE", "write_package"]
