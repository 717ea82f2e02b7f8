"""Every few-shot example of every prompt file runs in the sandbox against a real scene and succeeds.

The original CapRavens planner prompt had 42 examples, several of them invalid Python.  Here each
example states its scene (``#@ scene``) and what success means (``#@ task`` predicate,
``#@ check`` expressions, ``#@ expect`` values); this test builds the MuJoCo world, runs the
example's code through the same LMP/sandbox path as LLM code and checks it.  Helper calls in
planner examples (``parse_obj_name`` / ``parse_position``) are answered by the helper prompt's own
example for that question, through the real LMP machinery.
"""

from __future__ import annotations

import dataclasses
import os

import numpy as np
import pytest

from capmj.agents.prompt_files import META, QUESTION, load_prompt, load_system_prompt
from capmj.agents.sandbox import run_code
from prompt_examples import (ALL_LMPS, HELPER_LMPS, ExampleLLM, build_context, examples, objects_line,
                             query_of, scene_specs, session_for)

PLANNER_TOKEN_TARGET = 8000


def _check(ctx_env: dict, example, extra: dict | None = None) -> None:
    env = dict(ctx_env)
    env.update(extra or {})
    for expr in example.meta.get("check", "").splitlines():
        if not expr.strip():
            continue
        ns = run_code(f"check_result = bool({expr})", env, filename="<check>")
        assert ns["check_result"] is True, f"{example.id}: check failed: {expr}"


def _close(value, expected, tol: float = 1e-3) -> bool:
    if isinstance(expected, (list, tuple)) and expected and isinstance(expected[0], (int, float)):
        arr = np.asarray(value, float).ravel()
        return arr.shape == (len(expected),) and np.allclose(arr, expected, atol=tol)
    if isinstance(expected, (list, tuple)) and expected and isinstance(expected[0], (list, tuple)):
        return len(value) == len(expected) and all(_close(v, e, tol) for v, e in zip(value, expected))
    return value == expected


@pytest.mark.parametrize("lmp", ALL_LMPS)
def test_stop_sequences_cut_a_run_on_into_the_next_example_and_nothing_else(lmp: str) -> None:
    """Each example's answer, followed as a small model writes it by the next example of the same
    prompt, is cut back to exactly that answer; no answer contains its own stop sequence."""
    from capmj.llm.stream import cut_at_stop

    prompt = load_prompt(lmp)
    assert prompt.stop, f"{lmp} declares no '#@ stop:'"
    bodies = [ex.body for ex in prompt.examples]
    for body, following in zip(bodies, bodies[1:] + bodies[:1]):
        answer = body.split("\n", 2)[2] if lmp != "parse_function" else body.split("\n", 1)[1]
        run_on = answer.rstrip("\n") + "\n\n" + following
        assert cut_at_stop(run_on, prompt.stop) == answer.rstrip("\n"), (lmp, answer[:80])
        assert cut_at_stop(answer, prompt.stop) == answer


@pytest.mark.parametrize("lmp", ALL_LMPS)
def test_prompt_file_is_well_formed(lmp: str) -> None:
    prompt = load_prompt(lmp)
    assert prompt.examples, f"{lmp} has no examples"
    assert META not in prompt.template, "metadata lines must be stripped from the sent prompt"
    assert prompt.template.count(QUESTION) == 1
    rendered = prompt.render("objects = []\n# test.")
    assert QUESTION not in rendered and rendered.rstrip().endswith("# test.")
    for ex in prompt.examples:
        assert "scene" in ex.meta, f"{lmp}/{ex.id} has no scene"
        assert ex.body in prompt.template, f"{lmp}/{ex.id}: body must appear verbatim in the prompt"
        compile(ex.body, f"<{lmp}/{ex.id}>", "exec")  # valid Python as shown to the model
        line = objects_line(ex)
        if line is not None:  # the objects line states the scene truthfully
            assert line == f"objects = {[s.name for s in scene_specs(ex)]!r}", f"{lmp}/{ex.id}"
    assert load_system_prompt().startswith("You are a task planning assistant who only answers with Python code.")


def test_planner_prompt_is_lean() -> None:
    os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
    import litellm

    system = load_system_prompt()
    planner = load_prompt("planner").render(
        "objects = ['fixed red zone with obj_id 1', 'movable small blue block with obj_id 2']\n# goal.")
    tokens = litellm.token_counter(model="gpt-4o-mini", messages=[
        {"role": "system", "content": system}, {"role": "user", "content": planner}])
    assert tokens <= PLANNER_TOKEN_TARGET, tokens


@pytest.mark.parametrize(("lmp", "example"), examples("planner"), ids=lambda v: getattr(v, "id", v))
def test_planner_example_succeeds(lmp: str, example) -> None:
    ctx = build_context(example)
    llm = ExampleLLM()
    session, api = session_for(ctx, llm)
    env = session.plan_env()
    env["goal"] = ctx.scene.goal
    code = session.prepare(example.body, env)
    assert code == example.body, "planner examples must not need function synthesis"
    run_code(code, env, filename=f"<planner/{example.id}>")
    assert ctx.attempt_primitives >= 1
    if "task" in example.meta:
        verdict = ctx.verdict()
        assert verdict.success, (example.id, verdict.diagnostics)
    else:
        ctx.world.settle(max_steps=1000)
    assert "task" in example.meta or "check" in example.meta, f"{example.id} states no success condition"
    _check(session.helper_env(), example)
    # every helper question the example asked was answered by a real helper example
    assert all(lmp in HELPER_LMPS for lmp, _ in llm.asked)


@pytest.mark.parametrize("example", load_prompt("multiturn_system.txt").examples, ids=lambda e: e.id)
def test_multiturn_example_runs_turn_by_turn_in_one_namespace(example) -> None:
    """The example conversation of ``prompts/multiturn_system.txt``: its blocks, run in order in one
    namespace on the example's scene (as ``--interaction multi`` runs turns), reach the task's
    predicate, and the conversation ends with FINISH."""
    blocks = [b.split("\n", 1)[1].split("```")[0] for b in example.body.split("```python")[1:]]
    assert len(blocks) >= 2 and example.body.rstrip().endswith("FINISH")
    goal = example.body.split("goal: ", 1)[1].split(")", 1)[0]
    ctx = build_context(dataclasses.replace(example, body=f"# {goal}\n"))
    session, _ = session_for(ctx, ExampleLLM())
    namespace: dict[str, object] = {}
    for i, block in enumerate(blocks, start=1):
        env = session.plan_env()
        env["objects"] = [o.name for o in ctx.world.objects]
        env.update(namespace)
        namespace.update(run_code(block, env, filename=f"<multiturn/{example.id}/turn {i}>"))
    assert "task" in example.meta
    verdict = ctx.verdict()
    assert verdict.success, (example.id, verdict.diagnostics)


@pytest.mark.parametrize(("lmp", "example"), examples("parse_obj_name") + examples("parse_position")
                         + examples("parse_question"),
                         ids=lambda v: getattr(v, "id", v))
def test_helper_example_returns_expected_value(lmp: str, example) -> None:
    ctx = build_context(example)
    llm = ExampleLLM()
    session, _ = session_for(ctx, llm)
    query, _code = query_of(example)
    description = query[2:].rstrip(".")
    value = getattr(session, lmp)(description)  # the real LMP path: render, extract, sandbox
    assert llm.asked and llm.asked[-1][0] == lmp
    assert "expect" in example.meta or "check" in example.meta, f"{example.id} states no expected value"
    if "expect" in example.meta:
        expected = example.json("expect")
        assert _close(value, expected), (example.id, value, expected)
    _check(session.helper_env(), example, {"ret_val": value})
    assert ctx.attempt_primitives == 0, "helper LMPs must not move anything"


@pytest.mark.parametrize(("lmp", "example"), examples("parse_function"), ids=lambda v: getattr(v, "id", v))
def test_parse_function_example_defines_working_function(lmp: str, example) -> None:
    ctx = build_context(example)
    session, _ = session_for(ctx)
    query, _code = query_of(example)
    site = query.removeprefix("# define function:").strip()
    name = site.split("=", 1)[-1].strip().split("(")[0].strip()
    source = session.parse_function(name, site)
    env = session.helper_env()
    ns = run_code(source, env, filename=f"<parse_function/{example.id}>")
    assert name in ns
    assert "check" in example.meta, f"{example.id} states no check"
    _check(env, example, {name: ns[name]})


@pytest.mark.parametrize(("lmp", "example"), examples("parse_completion"), ids=lambda v: getattr(v, "id", v))
@pytest.mark.parametrize("drop_first_line", [False, True], ids=["whole", "first-line-dropped"])
def test_parse_completion_example_judges_truth(lmp: str, example, drop_first_line: bool) -> None:
    """The text reporter's examples run through the real reporter (pre-bound names, sandbox) and
    judge their scene right; with the example's first code line dropped (what a small model did)
    they still reach a verdict."""
    from capmj.agents.report.text import TextReporter

    ctx = build_context(example)
    llm = ExampleLLM()
    if drop_first_line:
        llm = ExampleLLM(drop_first_code_line=True)
    session, _ = session_for(ctx, llm)
    query, _code = query_of(example)
    goal = query.removeprefix("# goal:").strip()
    report = TextReporter().judge(session, ctx, goal)
    assert [lmp for lmp, _ in llm.asked] == ["parse_completion"], "the first answer must give the verdict"
    assert report.source == "code" and report.error is None, report
    if drop_first_line:
        assert report.verdict is not None, report
        return
    expected = example.json("expect")
    assert isinstance(expected, bool)
    assert report.verdict is expected, (example.id, report)
    assert report.reason, "reporter examples explain their verdict"
    call = next(c for c in session.transcript if c.lmp == "parse_completion")
    assert call.result is not None and f"wrong = {list(report.wrong)!r}" in call.result
    _check(session.helper_env(), example, {"wrong": list(report.wrong), "judge": report.verdict})
    if "task" in example.meta:  # when a task predicate applies, it agrees
        assert ctx.verdict().success is expected


@pytest.mark.parametrize(("text", "message"), [
    ("#@ example: a\nx = 1\n<<QUESTION>>\n", "has no '#@ end'"),
    ("#@ end\n<<QUESTION>>\n", "outside an example"),
    ("#@ example: a\n#@ end\n#@ example: a\n#@ end\n<<QUESTION>>\n", "duplicate example ids"),
    ("x = 1\n", "no <<QUESTION>> placeholder"),
    ("#@ example: a\n#@ example: b\n#@ end\n<<QUESTION>>\n", "starts inside"),
])
def test_malformed_prompt_files_are_rejected(tmp_path, text: str, message: str) -> None:
    from capmj.errors import ConfigError

    (tmp_path / "bad.py").write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_prompt("bad", tmp_path)
