"""Helper LMP code may call the helper LMPs itself, as CapRavens' examples do, to a bounded depth."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.lmp.session import LMPSession
from capmj.errors import PlanError
from capmj.sim.objects import ObjectSpec
from test_api import make_ctx

ANSWERS = {
    # parse_position asks parse_obj_name for the objects it measures (CapRavens' pattern)
    "the point between the red and the blue block":
        "blocks = parse_obj_name('the red and the blue block', f'objects = {get_obj_names()}')\n"
        "ps = [get_obj_pos(b) for b in blocks]\n"
        "ret_val = [(ps[0][0] + ps[1][0]) / 2, (ps[0][1] + ps[1][1]) / 2]\n",
    "the red and the blue block":
        "ret_val = [n for n in objects if get_color(n) in ('red', 'blue')]\n",
    # two helpers asking each other forever
    "ping": "ret_val = parse_position('pong')\n",
    "pong": "ret_val = parse_obj_name('ping')\n",
}


def fake_llm(messages, purpose="", stop=()):
    query = [ln for ln in messages[-1]["content"].splitlines() if ln.startswith("# ")][-1][2:].rstrip(".")
    return SimpleNamespace(text=f"```python\n{ANSWERS[query]}```", cached=False)


@pytest.fixture()
def session():
    ctx = make_ctx([ObjectSpec(1, "block", "red", (0.4, -0.1, 0.02), size="small"),
                    ObjectSpec(2, "block", "blue", (0.6, 0.1, 0.02), size="small")])
    api = PlannerAPI(ctx)
    return LMPSession(complete=fake_llm, api=api.functions(), objects_text=api.objects_text)


def test_helper_code_calls_another_helper(session):
    assert session.parse_position("the point between the red and the blue block") == pytest.approx([0.5, 0.0], abs=1e-3)
    assert [c.lmp for c in session.transcript] == ["parse_position", "parse_obj_name"]


def test_nesting_is_bounded(session):
    with pytest.raises(PlanError, match="max_helper_depth"):
        session.parse_obj_name("ping")
    assert len(session.transcript) == session.max_helper_depth
