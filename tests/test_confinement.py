"""Confinement of LLM-written task code (issue #25): each layer on its own, against a hostile corpus.

The corpus (``tests/hostile_candidates.py``) is the good candidate with one door to the operating
system added.  Every module must be refused by the static check with a message naming its door;
fed to the real check worker with the static check bypassed, the runtime guard must stop it with
the event recorded and leave no file, process or connection behind; where Linux allows
namespaces, the OS layer alone must keep files and network untouched.
"""

from __future__ import annotations

import ast
import importlib
import os
from pathlib import Path
from types import ModuleType

import pytest

from capmj.confine import allowlist
from capmj.confine.guard import opens_for_writing
from capmj.confine.names import name_findings
from capmj.generate.static import static_checks
from generator_script import CANDIDATES
from hostile_candidates import BY_ID, CORPUS, NAME, Hostile, run_hostile

GOOD_FILES = ("good_zone_color.py", "good_block_in_bowl.py", "good_stack_in_zone.py")


# --------------------------------------------------------------------------------------- allow-list
def test_every_allowed_name_exists_and_lends_no_module():
    """A listed name is a real member, never a module, and none of its public attributes is one
    (else ``allowed.attr`` would be a door the name check cannot see)."""
    for module_name in allowlist.IMPORTABLE:
        if module_name == "__future__":
            continue
        module = importlib.import_module(module_name)
        names = allowlist.members(module_name)
        assert names, module_name
        for n in names:
            obj = getattr(module, n)
            assert not isinstance(obj, ModuleType), f"{module_name}.{n} is a module"
            for a in dir(obj):
                if not a.startswith("_"):
                    assert not isinstance(getattr(obj, a, None), ModuleType), f"{module_name}.{n}.{a} is a module"


def test_the_prompt_documents_exactly_the_allowed_names():
    from capmj.generate.library import api_reference

    text = allowlist.allowed_imports_text() + "\n" + api_reference()
    for module_name in allowlist.IMPORTABLE:
        assert module_name in text
    for module_name in allowlist.CAPMJ_API:
        documented = {ln.split("(")[0].split(" ")[0].split(":")[0] for ln in api_reference().splitlines()}
        assert allowlist.members(module_name) <= documented, module_name
    assert "get_type_hints" not in text and "f2py" not in text


# --------------------------------------------------------------------------------------- static layer
@pytest.mark.parametrize("file", GOOD_FILES)
def test_good_candidates_pass_the_static_check(file):
    assert all(r.passed for r in static_checks((CANDIDATES / file).read_text())), static_checks(
        (CANDIDATES / file).read_text())


@pytest.mark.parametrize("hostile", CORPUS, ids=lambda h: h.id)
def test_static_check_refuses_every_door_and_names_it(hostile: Hostile, tmp_path):
    code = hostile.module(tmp_path / "marker", tmp_path / "victim", 9)
    bad = next((r for r in static_checks(code) if r.outcome == "fail"), None)
    assert bad is not None, f"{hostile.id} passed the static check"
    assert hostile.static in bad.detail, bad.detail


@pytest.mark.parametrize("code, words", [
    ("from capmj.tasks import predicates as P\nP.in_zone = lambda *a: True\n", "must not change the modules"),
    ("import numpy as np\nm = np\n", "used as a value"),
    ("import numpy as np\nnp = 3\n", "do not rebind it"),
    ("import numpy as np\nx = np.random.rand()\n", "draw from the rng argument"),
    ("from numpy.random import default_rng\n", "draw from the rng argument"),
    ("from capmj.tasks import *\n", "capmj.tasks.*"),
    ("import numpy.f2py\n", "import of 'numpy.f2py'"),
])
def test_static_check_refuses_module_tricks(code, words):
    bad = next(r for r in static_checks(code) if r.outcome == "fail")
    assert words in bad.detail, bad.detail


def test_dotted_paths_through_allowed_modules_pass():
    ok = ("import numpy as np\nimport capmj.tasks.predicates\nfrom numpy import linalg\n"
          "x = np.linalg.norm(np.zeros(3)) + linalg.det(np.ones((2, 2))) + np.pi.real\n"
          "y = capmj.tasks.predicates.in_zone\n")
    assert name_findings(ast.parse(ok)) == []
    assert [str(f) for f in name_findings(ast.parse(ok + "z = np.eye(2)\n"))] == [
        "line 6: np.eye (numpy.eye) is not part of the task API"]


def test_write_detection_reads_modes_and_flags():
    assert opens_for_writing(("f", "w", 0)) and opens_for_writing(("f", "rb+", 0)) and opens_for_writing(("f", "x", 0))
    assert opens_for_writing(("f", None, os.O_WRONLY)) and opens_for_writing(("f", None, os.O_RDONLY | os.O_CREAT))
    assert not opens_for_writing(("f", "r", os.O_RDONLY | os.O_CLOEXEC)) and not opens_for_writing(("f", "rb", 0))


# --------------------------------------------------------------------------------------- runtime layer
RUNTIME_SAMPLE = ("registry-os-system", "in-sample-scene", "raw-os-open-write", "remove-victim", "socket-connect",
                  "ctypes-libc-system", "import-module-new", "os-fork", "atexit-deferred", "patch-trusted-runner",
                  "exec-spoofed-filename")
"""One module per door class (the full corpus runs in ``benchmarks/confinement.py``)."""


@pytest.mark.parametrize("hostile_id", RUNTIME_SAMPLE)
def test_runtime_guard_alone_stops_the_door_and_records_the_event(hostile_id, tmp_path):
    hostile = BY_ID[hostile_id]
    run, traces = run_hostile(hostile, tmp_path, os_layer=False)
    assert run.violation is not None, (hostile.id, run.ended, run.results)
    assert run.violation["event"].startswith(hostile.events), run.violation
    assert traces == [], traces
    assert run.ended.startswith("refused by the runtime guard")
    failed = [r for r in run.results if r.outcome != "pass"]
    assert failed[0].outcome == "error" and "refused by the runtime guard" in failed[0].detail
    if hostile.where == "sample_scene":
        assert failed[0].name == "scenes"


def test_runtime_guard_passes_the_good_candidate(tmp_path):
    good = Hostile("none", "none", "", "", ())
    run, traces = run_hostile(good, tmp_path)
    assert run.violation is None and run.ended == "completed" and traces == []
    assert all(r.passed for r in run.results), run.results


def _os_layer_available(tmp_path: Path) -> dict:
    run, _ = run_hostile(Hostile("none", "none", "", "", ()), tmp_path, guarded=False)
    return run.os_layer or {}


@pytest.mark.parametrize("hostile_id", ("raw-os-open-write", "registry-os-system", "remove-victim", "socket-connect"))
def test_os_layer_alone_keeps_files_and_network_untouched(hostile_id, tmp_path):
    probe = tmp_path / "probe"
    probe.mkdir()
    report = _os_layer_available(probe)
    if not (report.get("network") and report.get("read_only")):
        pytest.skip(f"this machine does not allow the OS layer: {report}")
    work = tmp_path / "work"
    work.mkdir()
    run, traces = run_hostile(BY_ID[hostile_id], work, guarded=False)
    assert run.violation is None  # the guard was off: only the OS layer stood in the way
    assert traces == [], traces


# --------------------------------------------------------------------------------------- the generator
def test_a_candidate_past_a_broken_static_check_is_refused_at_runtime_without_repair(tmp_path, monkeypatch):
    """If the static check had a hole, the guard still rejects: no repair round, nothing packaged."""
    import capmj.generate.candidate as cand
    from capmj.generate import GenerateConfig, generate
    from capmj.taskcheck import CheckResult
    from generator_script import GeneratorScript, ScriptedCandidate
    from llm_stub_server import StubLLMServer

    monkeypatch.setattr(cand, "static_checks", lambda code: tuple(CheckResult(n, "pass") for n in
                                                                  ("parse", "imports", "names")))
    code = BY_ID["registry-os-system"].module(tmp_path / "marker", tmp_path / "victim", 9)
    hostile = ScriptedCandidate("hostile.py", NAME, "Put every block in the zone of its color.", "static:load",
                                code, code)
    with StubLLMServer(responder=GeneratorScript([hostile])) as server:
        result = generate(GenerateConfig(mode="top-down", name=NAME, description=hostile.goal, model="openai/stub",
                                         api_base=server.base_url, out=tmp_path / "out", seeds=1, accept_rate=1.0,
                                         cache_dir=tmp_path / "cache", timeout_s=30))
        calls = len(server.requests)
    rec = result.records[0]
    assert not rec.accepted and not rec.repaired and calls == 2  # pick examples, write: no repair, no vote
    assert rec.reason.startswith("refused by the runtime guard: os.system") and rec.stage == "static"
    assert not (tmp_path / "marker").exists() and not (tmp_path / "out" / "pyproject.toml").exists()
