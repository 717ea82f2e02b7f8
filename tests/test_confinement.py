"""Confinement of LLM-written task code (issue #25): each layer on its own, against a hostile corpus.

The corpus (``tests/hostile_candidates.py``) is the good candidate with one door to the operating
system added.  Every module must be refused by the static check with a message naming its door.
Checked with the static check bypassed, its code runs in the jail: the runtime guard there names
the event where it can see one; with the guard switched off (as code that reached the interpreter
could), the jail alone leaves no file, process or connection behind on the host; what the guard
cannot see at all (a write without an audit event, forged frames, a read of the environment, a
patched shared module) is stopped by the jail or the wire.
"""

from __future__ import annotations

import ast
import importlib
import os
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


# --------------------------------------------------------------------------------------- the guard, the jail
GUARD_SAMPLE = ("registry-os-system", "in-sample-scene", "raw-os-open-write", "remove-victim", "socket-connect",
                "ctypes-libc-system", "import-module-new", "os-fork", "patch-trusted-runner", "exec-spoofed-filename",
                "match-keyword-read", "rebuilt-code-object", "sleeper-module-name", "post-check-rewrite")
"""One module per door class the guard names (the full corpus runs in ``benchmarks/confinement.py``)."""


@pytest.mark.jail
@pytest.mark.parametrize("hostile_id", GUARD_SAMPLE)
def test_the_guard_in_the_jail_names_the_door_and_nothing_reaches_the_host(hostile_id, tmp_path):
    hostile = BY_ID[hostile_id]
    assert hostile.stops == "guard"
    run, traces = run_hostile(hostile, tmp_path)
    assert run.violation is not None, (hostile.id, run.ended, run.results)
    assert run.violation["event"].startswith(hostile.events), run.violation
    assert traces == [], traces
    assert run.ended.startswith("refused by the runtime guard")
    failed = [r for r in run.results if r.outcome != "pass"]
    assert failed[0].outcome == "error" and "refused by the runtime guard" in failed[0].detail
    if hostile.where == "sample_scene":
        assert failed[0].name == "scenes"


@pytest.mark.jail
def test_the_guard_passes_the_good_candidate(tmp_path):
    good = Hostile("none", "none", "", "", ())
    run, traces = run_hostile(good, tmp_path)
    assert run.violation is None and run.ended == "completed" and traces == []
    assert all(r.passed for r in run.results), run.results


JAIL_SAMPLE = ("raw-os-open-write", "registry-os-system", "remove-victim", "socket-connect", "os-fork", "os-execv",
               "write-without-audit-event", "guard-switched-off", "rebuilt-code-object", "post-check-rewrite",
               "orphan-process", "ctypes-libc-system", "signal-parent")


@pytest.mark.jail
@pytest.mark.parametrize("hostile_id", JAIL_SAMPLE)
def test_the_jail_alone_leaves_no_trace_on_the_host(hostile_id, tmp_path):
    """The guard switched off (as a candidate that reached the interpreter could): the OS boundary holds."""
    run, traces = run_hostile(BY_ID[hostile_id], tmp_path, guarded=False)
    assert run.violation is None and run.jail is not None and run.jail["guard"] is False
    assert traces == [], traces


@pytest.mark.jail
@pytest.mark.parametrize("hostile_id", [h.id for h in CORPUS if h.stops != "guard"])
def test_doors_the_guard_cannot_see_are_stopped_by_the_jail_or_the_wire(hostile_id, tmp_path):
    hostile = BY_ID[hostile_id]
    run, traces = run_hostile(hostile, tmp_path)
    assert run.violation is None and traces == [], (run.violation, traces)
    if hostile.stops == "harmless":
        return
    assert not all(r.passed for r in run.results), "a hostile candidate was accepted"
    if hostile.stops == "wire":
        assert "WireError" in run.results[0].detail, run.results[0]


@pytest.mark.jail
def test_jailed_code_cannot_read_a_key_planted_in_the_parent(tmp_path, monkeypatch):
    """A format-string read of the environment finds the jail's clean environment, not the parent's."""
    monkeypatch.setenv("OPENAI_API_KEY", "sk-planted-in-the-parent")
    run, _ = run_hostile(BY_ID["format-string-environ"], tmp_path)
    load = run.results[0]
    assert load.outcome == "error" and "environ(" in load.detail  # the read happened, in the jail
    assert "sk-planted" not in load.detail and "OPENAI_API_KEY" not in load.detail


@pytest.mark.jail
def test_a_shared_predicate_patched_in_the_jail_stays_intact_here(tmp_path):
    from capmj.tasks import predicates

    before = predicates.in_zone
    run, _ = run_hostile(BY_ID["reduce-hook-patch"], tmp_path)
    assert predicates.in_zone is before
    bad = next(r for r in run.results if r.outcome != "pass")
    assert bad.name == "not_solved_at_reset" and "already a success" in bad.detail  # its own lie, caught here


@pytest.mark.jail
def test_the_module_runs_under_its_installed_name_at_the_checks(tmp_path):
    """A sleeper keyed on its module name sees the name it will have once installed."""
    from hostile_candidates import MODULE

    code = GOOD_TEXT().replace("        return Scene(", "        assert __name__ == " + repr(MODULE) + ", __name__\n"
                               "        return Scene(")
    from capmj.confine.jail import Limits
    from capmj.confine.proxy import ModuleSource
    from capmj.generate.isolate import run_isolated

    run = run_isolated(ModuleSource(MODULE, code), name=NAME, seeds=(0,), accept_rate=1.0, tags=("generated-by-llm",),
                       limits=Limits(cpu_s=60, wall_s=120))
    assert all(r.passed for r in run.results), run.results


def GOOD_TEXT() -> str:  # noqa: N802 - reads like the constant it stands for
    return (CANDIDATES / "good_zone_color.py").read_text()


# --------------------------------------------------------------------------------------- the generator
@pytest.mark.jail
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
    assert rec.reason.startswith("refused by the runtime guard: import") and rec.stage == "static"
    assert not (tmp_path / "marker").exists() and not (tmp_path / "out" / "pyproject.toml").exists()


@pytest.mark.jail
def test_a_module_the_compiler_cannot_take_is_rejected_with_its_reason_and_the_journal_kept(tmp_path):
    """A 1 200-term sum makes ``compile`` raise ``RecursionError``: a parse failure, not a crash."""
    import json

    from capmj.generate import GenerateConfig, generate
    from generator_script import GeneratorScript, ScriptedCandidate
    from llm_stub_server import StubLLMServer

    deep = GOOD_TEXT().replace("        k = int(rng.integers(2, 4))",
                               "        k = int(rng.integers(2, 4)) + " + " + ".join(["0"] * 1200))
    cand = ScriptedCandidate("deep.py", NAME, "Put every block in the zone of its color.", "static:parse", deep, deep)
    with StubLLMServer(responder=GeneratorScript([cand])) as server:
        result = generate(GenerateConfig(mode="top-down", name=NAME, description=cand.goal, model="openai/stub",
                                         api_base=server.base_url, out=tmp_path / "out", seeds=1, accept_rate=1.0,
                                         cache_dir=tmp_path / "cache", timeout_s=30))
    rec = result.records[0]
    assert not rec.accepted and rec.stage == "static" and "RecursionError" in rec.reason, rec.reason
    line = json.loads((tmp_path / "out" / "generation.jsonl").read_text())
    assert line["stage"] == "static" and "RecursionError" in line["reason"]
