"""The task generator end to end through a real OpenAI-compatible HTTP server on 127.0.0.1.

The server's answers are scripted fixtures (tests/generator_script.py, candidate modules in
tests/generator_candidates/); everything else is real: prompt files, litellm HTTP, the LLM cache,
the AST checks, the limited worker process, MuJoCo physics with the oracle, the package writer,
pip installing the package into a fresh virtualenv and a benchmark run from it.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from capmj.generate import GenerateConfig, Limits, generate
from capmj.generate.cli import main as cli_main
from capmj.generate.package import TEST_FILE
from capmj.generate.static import extract_code, static_checks
from generator_script import GeneratorScript, ScriptedCandidate, candidate
from llm_stub_server import StubLLMServer, iter_prompts
from venvs import make_venv, pip_install

pytestmark = pytest.mark.jail

PACKAGE = "capmj-generated-test"
GOOD = "put-blocks-in-zone-of-same-color"


def config(server: StubLLMServer, root: Path, out: str, **kw) -> GenerateConfig:
    kw.setdefault("mode", "bottom-up")
    kw.setdefault("seeds", 2)
    return GenerateConfig(model="openai/stub", api_base=server.base_url, out=root / out, package=PACKAGE,
                          accept_rate=1.0, cache_dir=root / "cache", timeout_s=30, **kw)


def checks_of(rec, stage: str | None = None, attempt: int | None = None) -> dict[str, dict]:
    return {c["name"]: c for c in rec.checks if (stage is None or c["stage"] == stage)
            and (attempt is None or c["attempt"] == attempt)}


def package_files(out: Path) -> dict[str, str]:
    skip = {"generation.jsonl"}
    return {str(p.relative_to(out)): p.read_text() for p in sorted(out.rglob("*"))
            if p.is_file() and p.name not in skip and "conversations" not in p.parts and "__pycache__" not in p.parts
            and ".egg-info" not in str(p)}


# --------------------------------------------------------------------------------------- static
def test_static_checks_reject_without_running():
    assert [r.outcome for r in static_checks("import os\nx = 1\n")] == ["pass", "fail", "skip"]
    assert static_checks("from ..x import y\n")[1].outcome == "fail"
    bad = static_checks("import numpy as np\ndef f(rng):\n    return open('/etc/passwd').read()\n")
    assert bad[2].outcome == "fail" and "'open'" in bad[2].detail
    rnd = static_checks("import numpy as np\ndef sample_scene(rng: np.random.Generator):\n    return np.random.rand()\n")
    assert rnd[2].outcome == "fail" and "np.random.rand" in rnd[2].detail
    assert static_checks("x = (\n")[0].outcome == "fail"
    ok = static_checks("from __future__ import annotations\nimport math\nfrom capmj.tasks.spawn import Spawner\n")
    assert all(r.passed for r in ok)
    assert extract_code("text\n```python\nx = 1\n```\nmore") == "x = 1\n"


def test_a_syntax_error_shows_the_lines_that_lead_to_it():
    # a 1.5B model's real mistake: a continuation line without brackets; the repair turn must show line 2
    code = 'def f(x):\n    why = f"{x} is not "\n                f"in the zone"\n    return why\n'
    detail = static_checks(code)[0].detail
    assert "(line 3)" in detail and '    2 |     why = f"{x} is not "' in detail and '>    3 |' in detail
    assert "line 4" not in detail and "return why" not in detail


# --------------------------------------------------------------------------------------- CLI input
@pytest.mark.parametrize("argv, words", [
    (["--mode", "top-down", "--model", "m", "--out", "OUT"], "--name"),
    (["--mode", "sideways", "--model", "m", "--out", "OUT"], "invalid choice"),
    (["--mode", "bottom-up", "--model", "m", "--out", "OUT", "--accept-rate", "1.5"], "accept-rate"),
    (["--mode", "bottom-up", "--model", "m", "--out", "OUT", "--n", "0"], "--n"),
])
def test_cli_bad_input_is_one_line_exit_2(tmp_path, capsys, argv, words):
    argv = [str(tmp_path / "o") if a == "OUT" else a for a in argv]
    with pytest.raises(SystemExit) as e:
        raise SystemExit(cli_main(argv))
    assert e.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("error:") and words in err


def test_cli_refuses_a_non_empty_out(tmp_path, capsys):
    (tmp_path / "keep.txt").write_text("results")
    assert cli_main(["--mode", "bottom-up", "--model", "m", "--out", str(tmp_path)]) == 2
    assert "not an empty folder" in capsys.readouterr().err
    assert (tmp_path / "keep.txt").read_text() == "results"


# --------------------------------------------------------------------------------------- good task
def test_good_task_repaired_checked_packaged_installed_and_run(tmp_path):
    script = GeneratorScript([candidate("broken_syntax.py", repair="good_zone_color.py", name=GOOD)])
    with StubLLMServer(responder=script) as server:
        cfg = config(server, tmp_path, "out", mode="top-down", name=GOOD, seeds=1,
                     description="Put every block in the zone of its color.")
        result = generate(cfg)
        calls = len(server.requests)
        assert calls == 4  # pick examples, write, repair, reflect (top-down has no proposal call)
        rec = result.records[0]
        assert rec.accepted and rec.stage == "accepted" and result.accepted == (GOOD,), rec.reason
        first = checks_of(rec, attempt=1)
        assert first["parse"]["outcome"] == "fail" and "never closed" in first["parse"]["detail"]
        assert "load" not in first  # nothing ran before the repair
        assert rec.repaired
        final = checks_of(rec, attempt=2)
        assert [c["stage"] for c in final.values()] == ["static"] * 5 + ["runtime"] * 6
        assert all(c["outcome"] == "pass" for c in final.values())
        assert rec.oracle_rate == 1.0 and final["oracle_solves"]["data"]["seeds"] == 1
        assert rec.reflection == {"vote": "accept", "reason": "scripted vote"}
        assert rec.examples == ["stack-all-blocks-on-a-zone", "put-block-into-matching-bowl"]

        out = cfg.out
        line = json.loads((out / "generation.jsonl").read_text().splitlines()[0])
        assert line["stage"] == "accepted" and line["usage"]["calls"] == 4 and line["usage"]["prompt_tokens"] > 0
        log = json.loads((out / line["conversation"]).read_text())
        roles = [m["role"] for m in log["messages"]]
        assert roles == ["system"] + ["user", "assistant"] * 4 and len(log["turns"]) == 4
        assert "class StackAllBlocksOnAZone" in log["messages"][-6]["content"]  # the examples' source was sent
        pyproject = (out / "pyproject.toml").read_text()
        assert f'"{GOOD}" = "capmj_generated_test.put_blocks_in_zone_of_same_color:TASK"' in pyproject
        assert "generated-by-llm" in pyproject
        readme = (out / "README.md").read_text()
        assert "Put every block in the zone of its color." in readme and "oracle solved 1/1 seeds" in readme
        assert (out / TEST_FILE).is_file()

        # a rerun from the LLM cache: no HTTP call, the same package
        server.reset()
        again = generate(config(server, tmp_path, "again", mode="top-down", name=GOOD, seeds=1,
                                description="Put every block in the zone of its color."))
        assert server.requests == [] and again.accepted == (GOOD,)
        assert package_files(out) == package_files(again.out)
        assert json.loads((again.out / "generation.jsonl").read_text())["usage"]["cached_calls"] == 4

    # install into a fresh virtualenv; the registry lists it and a bench grid solves it with the oracle
    py = make_venv(tmp_path / "venv")
    env = {k: v for k, v in os.environ.items() if k not in ("CAPMJ_DISABLE_PLUGINS", "PYTHONPATH")}
    pip = pip_install(py, "--no-build-isolation", "-e", str(out), env=env)
    assert pip.returncode == 0, pip.stderr
    listed = subprocess.run([str(py), "-m", "capmj.bench", "--list"], capture_output=True, text=True, timeout=120,
                            env=env, cwd=tmp_path)
    assert listed.returncode == 0 and GOOD in listed.stdout and PACKAGE in listed.stdout, listed.stdout + listed.stderr
    run = tmp_path / "bench"
    bench = subprocess.run([str(py), "-m", "capmj.bench", "--tasks", "generated-by-llm", "--seeds", "10001",
                            "--workers", "0", "--no-log", "--no-progress", "--out", str(run)],
                           capture_output=True, text=True, timeout=300, env=env, cwd=tmp_path)
    assert bench.returncode == 0, bench.stderr
    episodes = [json.loads(x) for x in (run / "episodes.jsonl").read_text().splitlines()]
    assert [(e["task"], e["success"]) for e in episodes] == [(GOOD, True)], [(e.get("error"), e.get("error_type")) for e in episodes]


# --------------------------------------------------------------------------------------- rejections

    # accepted means confined: the manifest names the module's sha256; `tasks check` re-checks it
    manifest = json.loads((out / "capmj_generated_test" / "capmj-confinement.json").read_text())
    module = out / "capmj_generated_test" / "put_blocks_in_zone_of_same_color.py"
    entry = manifest["tasks"][GOOD]
    assert manifest["files"][entry["module"]] == hashlib.sha256(module.read_bytes()).hexdigest()
    assert entry["module"] == "put_blocks_in_zone_of_same_color.py" and set(manifest["files"]) == {"__init__.py", entry["module"]}
    assert entry["confinement"]["static"] == ["parse", "imports", "names"] and entry["confinement"]["jail"]["jail"] == "bwrap"
    assert entry["facts"]["name"] == GOOD and entry["facts"]["tags"] == ["generated-by-llm"]
    check = subprocess.run([str(py), "-m", "capmj.tasks", "check", GOOD, "--seeds", "1"], capture_output=True,
                           text=True, timeout=300, env=env, cwd=tmp_path)
    assert check.returncode == 0 and "PASS  confinement" in check.stdout, check.stdout + check.stderr
    marker = tmp_path / "edited-module-ran"
    module.write_text(module.read_text().replace(
        "from capmj.tasks.spawn import Spawner, pick_colors\n",
        f"from capmj.tasks.spawn import Spawner, pick_colors\nopen({str(marker)!r}, 'w').close()\n"))
    check = subprocess.run([str(py), "-m", "capmj.tasks", "check", GOOD, "--seeds", "1"], capture_output=True,
                           text=True, timeout=300, env=env, cwd=tmp_path)
    assert check.returncode == 1 and "FAIL  confinement" in check.stdout, check.stdout + check.stderr
    assert "edited after acceptance" in check.stdout and "'open' is not allowed" in check.stdout
    bench = subprocess.run([str(py), "-m", "capmj.bench", "--tasks", GOOD, "--seeds", "10001", "--workers", "0",
                            "--no-log", "--no-progress", "--out", str(tmp_path / "bench-edited")],
                           capture_output=True, text=True, timeout=300, env=env, cwd=tmp_path)
    assert bench.returncode != 0 and "fails its confinement check, so it is not imported" in bench.stderr, bench.stderr
    assert not marker.exists()  # the edited module never ran


def test_generator_asks_for_sample_scene_and_refuses_the_old_name_naming_the_new_one(tmp_path):
    """A candidate that writes the deprecated ``generate`` fails ``protocol`` in the worker; the
    repair turn tells the model to rename it (here the scripted repair does not, so it is rejected)."""
    good = candidate("good_zone_color.py", name=GOOD)
    old = good.code.replace("def sample_scene(", "def generate(")
    assert old != good.code
    script = GeneratorScript([ScriptedCandidate("old_name.py", GOOD, good.goal, "static:protocol", old, old)])
    with StubLLMServer(responder=script) as server:
        result = generate(config(server, tmp_path, "out", mode="top-down", name=GOOD, seeds=1,
                                 description="Put every block in the zone of its color."))
        system = str(server.requests[0]["messages"][0]["content"])
        repair = [r for r in iter_prompts(server) if "was rejected by the check" in r]
    assert "sample_scene(self, rng) -> Scene" in system and "generate(self, rng)" not in system
    rec = result.records[0]
    assert not rec.accepted and rec.stage == "static" and rec.repaired
    first = checks_of(rec, attempt=1)
    assert first["load"]["outcome"] == "pass" and first["protocol"]["outcome"] == "fail"
    assert "rename it to 'sample_scene'" in first["protocol"]["detail"]
    assert len(repair) == 1 and "rename it to 'sample_scene'" in repair[0]
    assert rec.reason.startswith("static check protocol failed after the repair round") and "sample_scene" in rec.reason


def test_broken_candidates_rejected_at_their_stage(tmp_path, monkeypatch):
    monkeypatch.setenv("CAPMJ_MARKER_DIR", str(tmp_path))  # broken_import_os would create 'ran' here
    files = ["broken_import_os.py", "broken_open_call.py", "broken_solved_at_reset.py", "broken_wrong_zone.py",
             "broken_absent_colour.py"]
    cands = [candidate(f) for f in files]
    journal: list[list[int]] = []  # what generation.jsonl holds each time a candidate finishes

    def done(rec):
        lines = (tmp_path / "out" / "generation.jsonl").read_text().splitlines()
        journal.append([json.loads(x)["index"] for x in lines])
        assert json.loads(lines[-1])["index"] == rec.index

    with StubLLMServer(responder=GeneratorScript(cands)) as server:
        result = generate(config(server, tmp_path, "out", n=len(cands), workers=2), on_done=done)
    assert [len(x) for x in journal] == list(range(1, len(cands) + 1))  # kept as they finish, not at the end
    recs = {r.name: r for r in result.records}
    for c in cands:
        rec = recs[c.name]
        assert not rec.accepted and rec.stage == c.expect_stage, (c.name, rec.stage, rec.reason)
        final = checks_of(rec, attempt=max(x["attempt"] for x in rec.checks))
        assert final[c.expect_check]["outcome"] in ("fail", "error"), (c.name, rec.checks)
    assert not (tmp_path / "ran").exists()
    for name in ("broken-import-os", "broken-open-call"):
        assert {c["name"] for c in recs[name].checks} == {"parse", "imports", "names"}  # the worker never started
        assert recs[name].repaired  # one repair round, which did not help
    assert "'os'" in checks_of(recs["broken-import-os"])["imports"]["detail"]
    assert "'open'" in checks_of(recs["broken-open-call"])["names"]["detail"]
    assert recs["broken-wrong-zone"].oracle_rate == 0.0 and "rate 0.00" in recs["broken-wrong-zone"].reason
    assert "already a success" in checks_of(recs["broken-solved-at-reset"])["not_solved_at_reset"]["detail"]
    assert "no object is" in checks_of(recs["broken-absent-colour"])["goal_text"]["detail"]
    out = result.out
    assert not (out / "pyproject.toml").exists() and result.accepted == ()
    lines = [json.loads(x) for x in (out / "generation.jsonl").read_text().splitlines()]
    assert [x["index"] for x in lines] == list(range(len(cands)))
    assert all((out / x["conversation"]).is_file() for x in lines)
    assert "Rejected candidates" in (out / "README.md").read_text()


def test_endless_sample_scene_killed_by_cpu_limit_and_recorded(tmp_path):
    c = candidate("broken_while_true.py")
    with StubLLMServer(responder=GeneratorScript([c])) as server:
        result = generate(config(server, tmp_path, "out", limits=Limits(cpu_s=3, wall_s=120)))
    rec = result.records[0]
    assert not rec.accepted and rec.stage == "runtime"
    scenes = checks_of(rec)["scenes"]
    assert scenes["outcome"] == "error" and "CPU-time limit of 3 s" in scenes["detail"], scenes
    assert checks_of(rec)["oracle_solves"]["outcome"] == "skip"
    line = json.loads((result.out / "generation.jsonl").read_text())
    assert line["stage"] == "runtime" and "CPU-time limit" in line["reason"]


def test_cli_runs_a_generation_and_prints_verdicts(tmp_path, capsys):
    with StubLLMServer(responder=GeneratorScript([candidate("broken_import_os.py")])) as server:
        code = cli_main(["--mode", "bottom-up", "--n", "1", "--model", "openai/stub", "--api-base", server.base_url,
                         "--out", str(tmp_path / "out"), "--no-progress"])
    out = capsys.readouterr().out
    assert code == 0 and "broken-import-os" in out and "rejected at static" in out and "0 of 1 accepted" in out
    assert json.loads((tmp_path / "out" / "generation.jsonl").read_text())["stage"] == "static"


def test_runaway_allocation_stopped_by_the_memory_limit(tmp_path):
    from capmj.confine.proxy import ModuleSource
    from capmj.generate.isolate import run_isolated
    from generator_script import CANDIDATES

    code = (CANDIDATES / "good_zone_color.py").read_text().replace(
        "        k = int(rng.integers(2, 4))", "        k = int(np.ones(600_000_000).sum()) % 2 + 2  # 4.8 GB")
    run = run_isolated(ModuleSource("capmj_generated_test.hog", code), name=GOOD, seeds=(0,), accept_rate=1.0,
                       tags=("generated-by-llm",),
                       limits=Limits(cpu_s=60, memory_mb=2048, wall_s=120))
    scenes = {r.name: r for r in run.results}["scenes"]
    assert scenes.outcome == "error" and "MemoryError" in scenes.detail, run


def test_the_task_api_text_is_the_same_in_every_process() -> None:
    """The API reference is the generator's system message: two processes with different hash
    seeds must render it byte for byte alike (sets sorted), or the LLM cache misses on every rerun."""
    code = "import hashlib; from capmj.generate.library import api_reference as a; print(hashlib.sha256(a().encode()).hexdigest())"
    out = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          env={**os.environ, "PYTHONHASHSEED": seed}).stdout for seed in ("1", "2", "3")}
    assert len(out) == 1, out


def test_an_unreadable_proposal_gets_one_repair_and_json_with_comments_is_read(tmp_path):
    """The shared 1.5B model's first bottom-up proposal was JSON with a ``// comment`` and a ``...``
    item (copied from the prompt's old answer skeleton): such an answer is read; an answer with no
    JSON at all gets one repair request; two unusable answers stop the candidate at ``propose``."""
    c = candidate("broken_import_os.py")
    script = GeneratorScript([c])
    proposal = ('```json\n{\n  "name": "%s",\n  "goal": "%s",\n  "objects": ["blocks", ...],  // the objects\n'
                '  "why": "scripted",\n}\n```' % (c.name, c.goal))
    seen: list[str] = []

    def responder(request):
        last = str(request["messages"][-1]["content"])
        seen.append(last)
        if "Propose one NEW task" in last:
            return "A task where the robot sorts blocks. It is interesting."
        if "could not be read as a proposal" in last:
            return proposal
        return script(request)

    with StubLLMServer(responder=responder) as server:
        rec = generate(config(server, tmp_path, "out")).records[0]
    assert rec.name == c.name and rec.proposal["objects"] == ["blocks"] and rec.stage == "static"
    assert "no JSON value in the answer" in seen[1]
    assert [t["purpose"] for t in json.loads((tmp_path / "out" / rec.conversation).read_text())["turns"]][:2] == [
        "generate.propose", "generate.propose_repair"]

    with StubLLMServer(responder=lambda request: "no JSON here, sorry") as server:
        rec = generate(config(server, tmp_path, "out2")).records[0]
    assert rec.stage == "propose" and not rec.accepted and "after the repair round" in rec.reason
    assert rec.usage["calls"] == 2


def test_json_extras_are_dropped_only_outside_strings():
    from capmj.generate.static import extract_json
    assert extract_json('{"goal": "stack them ... // high", "n": [1, 2, ...], // note\n}') == {
        "goal": "stack them ... // high", "n": [1, 2]}
    assert extract_json('[{"a": "x\\"y // z"},]') == [{"a": 'x"y // z'}]
    assert extract_json('[..., 1, ..., ..., 2, ...]') == [1, 2]  # the commas of several dropped items
    assert extract_json('{"goal": "[, x , , ]", "n": [1, ...]}') == {"goal": "[, x , , ]", "n": [1]}
    with pytest.raises(ValueError):
        extract_json('{"a": 1 "b": 2}')  # still not JSON: the original error
