"""``python -m capmj.bench export RUN --bundle OUT.zip``: the evidence bundle of a small real run.

The run (tests/report_runs.py, made once for the module) is the LLM agent scripted through the
stub server on task A and task H × two seeds: on A the first plan fails and the second succeeds,
on H the server answers HTTP 400 (two anomalies, half the run: the page's first line says so).  The bundle must hold what a
leaderboard asks for and reproduce its own summary from its own files.
"""

from __future__ import annotations

import hashlib
import json
import shlex
import zipfile
from pathlib import Path
from typing import Any

import pytest
from report_runs import TASK, llm_run

from capmj.bench.cli import main
from capmj.bench.report import report

LABEL = "llm openai/stub (reporter=none)"
OTHER = "put-block-into-matching-bowl"


@pytest.fixture(scope="module")
def bundle(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("bundle")
    run = llm_run(root / "run", [TASK, OTHER], "10001,10003")
    out = root / "evidence.zip"
    assert main(["export", str(run), "--bundle", str(out)]) == 0
    return run, out


def _read(z: zipfile.ZipFile, name: str) -> Any:
    return json.loads(z.read(name))


def test_the_bundle_holds_the_evidence_a_leaderboard_asks_for(bundle: tuple[Path, Path]) -> None:
    run, out = bundle
    with zipfile.ZipFile(out) as z:
        names = set(z.namelist())
        assert {"evidence.json", "summary.json", "summary.md", "manifest.json", "episodes.jsonl", "config.json",
                "report.html", "versions.json", "reproduce.sh"} <= names
        assert not any(n.endswith(".rrd") for n in names)  # logs only with --with-rrd
        assert any(n.startswith("transcripts/") for n in names) and any(n.startswith("thumbs/") for n in names)
        facts = _read(z, "evidence.json")
        # every other file is listed with its SHA-256, and the run's files are copied unchanged
        assert set(facts["files"]) == names - {"evidence.json"}
        for name, sha in facts["files"].items():
            assert hashlib.sha256(z.read(name)).hexdigest() == sha, name
        assert z.read("episodes.jsonl") == (run / "episodes.jsonl").read_bytes()
        config = _read(z, "config.json")
        assert _read(z, "manifest.json") == config["manifest"]
        versions = _read(z, "versions.json")
        script = z.read("reproduce.sh").decode()
        page = z.read("report.html").decode()
    # model and harness revision, the figures, and the exact command
    assert facts["model"] == "openai/stub" and facts["agent"] == "llm"
    harness = facts["harness"]
    assert harness["capmj"] and harness["python"] and harness["mujoco"] and harness["litellm"]
    assert harness["git_revision"] == config["manifest"]["git"]["revision"]
    assert versions["run"]["capmj"] == versions["bundle"]["capmj"] == harness["capmj"]
    cell = facts["configurations"][LABEL]
    records = [json.loads(x) for x in (run / "episodes.jsonl").read_text().splitlines()]
    assert (cell["episodes_run"], cell["successes"]) == (4, 1) == (len(records), sum(r["success"] for r in records))
    assert (cell["episodes"], cell["inconclusive"], facts["inconclusive"]) == (2, 2, 2)  # H's provider failures apart
    assert cell["tokens"] == sum(r["llm"]["spend"]["tokens"] for r in records) > 0
    assert cell["stopped_by_limit"] == 0 and cell["failures"] == {"unknown_object": 1}
    assert cell["anomaly_labels"] == {"llm_error": 2}
    assert cell["per_solved_episode"]["tokens"] == cell["tokens"]  # one episode solved; H spent no token
    command = "python -m capmj.bench " + shlex.join(config["argv"])
    assert facts["reproduce"] == [command] and command in script.splitlines()
    assert f"git checkout {harness['git_revision']}" in script
    assert page.count('class="failed-episode agent"') == 1 and "data:image/png;base64," in page
    assert page.count('class="failed-episode anomaly"') == 2  # H's provider failures, marked apart
    assert 'id="headline"' in page and 'id="anomaly-count" data-count="2"' in page


def test_the_bundle_rebuilds_its_summary_from_its_own_files(bundle: tuple[Path, Path], tmp_path: Path) -> None:
    _, out = bundle
    with zipfile.ZipFile(out) as z:
        z.extractall(tmp_path / "unzipped")
    stored = json.loads((tmp_path / "unzipped" / "summary.json").read_text())
    rebuilt, _ = report([tmp_path / "unzipped"])
    rebuilt = json.loads(json.dumps(rebuilt, default=str))
    for summary in (stored, rebuilt):  # where the folder was, and the run's timing facts (kept from the run)
        summary.pop("sources")
        summary.pop("run", None)
        if "stamps" in summary:  # per source folder
            summary["stamps"] = sorted(summary["stamps"].values())
    assert rebuilt == stored
    assert stored["overall"][LABEL]["successes"] == 1


def test_a_folder_that_is_no_run_is_a_clear_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["export", str(tmp_path), "--bundle", str(tmp_path / "x.zip")]) == 2
    assert "is not a result folder" in capsys.readouterr().err and not (tmp_path / "x.zip").exists()


def test_with_rrd_the_logs_come_too(bundle: tuple[Path, Path], tmp_path: Path) -> None:
    from capmj.bench.bundle import write_bundle

    run, _ = bundle
    with zipfile.ZipFile(write_bundle(run, tmp_path / "with-logs.zip", with_rrd=True)) as z:
        logs = sorted(n for n in z.namelist() if n.endswith(".rrd"))
        assert logs == sorted(p.relative_to(run).as_posix() for p in (run / "rrd").rglob("*.rrd")) and len(logs) == 4
        assert z.read(logs[0]) == (run / logs[0]).read_bytes()
