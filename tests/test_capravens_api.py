"""CapRavens' names in capmj (docs/llm.md, "Porting CapRavens prompts"), on real worlds: what runs
as written, and the errors that name each deliberate difference.  Written from capmj's docs and
docstrings; no example of the original is copied here."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.base import EpisodeContext
from capmj.agents.lmp.session import LMPSession
from capmj.agents.report.text_env import reporter_env
from capmj.agents.sandbox import run_code
from capmj.errors import PlanError, PortingDifference
from capmj.sim.objects import ObjectSpec
from capmj.sim.world import World
from capmj.tasks.protocol import Scene

ZONE_YAW = math.pi / 4


def make_ctx(objects, seed: int = 3) -> EpisodeContext:
    scene = Scene(tuple(objects), "test scene")
    world = World(scene.objects)
    world.settle()
    return EpisodeContext(SimpleNamespace(name="capravens-api-test"), seed, scene, world)


@pytest.fixture(scope="module")
def scene():
    """A zone turned 45° (side 0.12 m: its world box reaches 0.085 m from the centre along x, the
    square only 0.06 m), a block inside the square, one in the box's corner outside the square, a
    bowl with a block in it and a free block."""
    objects = [
        ObjectSpec(1, "zone", "green", (0.5, 0.0, 0.0005), yaw=ZONE_YAW),
        ObjectSpec(2, "block", "red", (0.51, 0.01, 0.01), yaw=0.2, size="tiny"),
        ObjectSpec(3, "block", "blue", (0.43, -0.07, 0.01), yaw=0.0, size="tiny"),  # box corner, off the square
        ObjectSpec(4, "bowl", "yellow", (0.6, 0.3, 0.0175)),
        ObjectSpec(5, "block", "purple", (0.4, 0.3, 0.02), yaw=0.4, size="small"),
    ]
    ctx = make_ctx(objects)
    api = PlannerAPI(ctx)
    return api, api.functions(), ctx


def test_the_corner_block_is_in_the_zones_box_but_not_its_square(scene):
    """The premise of the containment tests below, measured on the world."""
    _api, f, ctx = scene
    xmin, ymin, _, xmax, ymax, _ = f["get_bbox"](1)
    x, y, _ = f["get_obj_pos"](3)
    assert xmin < x < xmax and ymin < y < ymax
    local = np.abs([(x - 0.5) * math.cos(ZONE_YAW) + y * math.sin(ZONE_YAW),
                    -(x - 0.5) * math.sin(ZONE_YAW) + y * math.cos(ZONE_YAW)])
    assert local.max() > 0.06


def test_bbox_contains_pt_uses_the_turned_square_and_the_bowls_disc(scene):
    _api, f, ctx = scene
    zone = ctx.world.objects_by_id[1].name
    assert f["bbox_contains_pt"](zone, ctx.world.objects_by_id[2].name) is True
    assert f["bbox_contains_pt"](container_name=zone, obj_name=ctx.world.objects_by_id[3].name) is False
    assert f["bbox_contains_pt"]("yellow bowl", "purple block") is False  # near-miss names, as elsewhere
    with pytest.raises(ValueError, match="two different objects"):
        f["bbox_contains_pt"](zone, zone)


def test_bbox_contains_pt_sees_a_block_put_in_a_bowl(scene):
    _api, f, ctx = make_scene_with_block_in_bowl()
    assert f["bbox_contains_pt"]("yellow bowl", "purple block") is True


def make_scene_with_block_in_bowl():
    ctx = make_ctx([ObjectSpec(1, "bowl", "yellow", (0.55, 0.1, 0.0175)),
                    ObjectSpec(2, "block", "purple", (0.4, -0.2, 0.02), yaw=0.4, size="small")])
    api = PlannerAPI(ctx)
    f = api.functions()
    f["put_first_on_second"]("purple block", "yellow bowl")
    ctx.world.settle(max_steps=1000)
    return api, f, ctx


def test_is_obj_visible_is_whether_the_name_resolves(scene):
    _api, f, ctx = scene
    assert f["is_obj_visible"](ctx.world.objects_by_id[4].name) is True
    assert f["is_obj_visible"]("purple block") is True  # near-miss, as every function accepts it
    assert f["is_obj_visible"](5) is True
    assert f["is_obj_visible"]("purple bowl") is False
    assert f["is_obj_visible"]("block") is False  # three blocks fit: nothing is guessed
    assert f["is_obj_visible"](99) is False


def test_is_target_occupied_of_several_positions_is_what_occupies_any(scene):
    _api, f, ctx = scene
    one = f["is_target_occupied"]([0.4, 0.3])
    two = f["is_target_occupied"]([[0.4, 0.3], ((0.6, 0.3, 0.02), (0, 0, 0, 1))], 0.01)
    assert one == [ctx.world.objects_by_id[5].name]
    assert two == [ctx.world.objects_by_id[5].name, ctx.world.objects_by_id[4].name]
    assert f["is_target_occupied"]([[0.3, -0.4], [0.7, -0.4]], 0.01) == []


def test_indexing_a_coordinate_names_the_one_element_list_difference(scene):
    _api, f, _ctx = scene
    pos = f["get_obj_pos"]("purple block")
    assert isinstance(pos, list) and len(pos) == 3
    assert pos[0] + 1.0 == pytest.approx(1.4, abs=0.01) and type(pos[0] + 1.0) is float
    assert np.array(pos).dtype == np.float64 and repr(pos[0]) == repr(float(pos[0]))
    for code in ("z = get_obj_pos('purple block')[0][2]",
                 "x, y, z = get_obj_pos('purple block')[0]",
                 "q = get_obj_rot('purple block')[0][3]",
                 "put_first_on_second('red block', get_obj_pos('purple block')[0])",
                 "p = utils.apply((get_obj_pos('fixed green zone with obj_id 1')[0], (0, 0, 0, 1)), (0.1, 0, 0))"):
        with pytest.raises(PlanError, match="not CapRavens' one-element list") as err:
            run_code(code, f)
        assert isinstance(err.value.__cause__, PortingDifference)
    ns = run_code("t = type(get_obj_pos('purple block')[0]) == float\nn = float(get_obj_pos(5)[2])", f)
    assert ns["t"] is True and ns["n"] == pytest.approx(0.02, abs=0.002)


def test_picking_a_fixed_object_is_a_porting_difference_shown_as_value_error(scene):
    _api, f, _ctx = scene
    with pytest.raises(PortingDifference, match="is fixed and cannot be picked") as err:
        f["put_first_on_second"]("yellow bowl", [0.5, 0.3])
    assert isinstance(err.value, ValueError)


@pytest.mark.parametrize(("name", "message"), [
    ("fixed purple block", "capmj has no fixed blocks.*'movable small purple block with obj_id 5'"),
    ("fixed purple block with obj_id 5", "capmj has no fixed blocks"),
    ("green zone with obj_id 0", "obj_ids count from 1"),
])
def test_names_only_capravens_scenes_had_say_why(scene, name: str, message: str):
    _api, f, _ctx = scene
    with pytest.raises(PortingDifference, match=message):
        f["get_obj_pos"](name)
    assert f["is_obj_visible"](name) is False


def test_utils_pose_helpers_agree_with_the_api(scene):
    """utils.quatXYZW_to_eulerXYZ of get_obj_rot is get_obj_pos_dict's Euler angles; the inverse
    gives the quaternion back; utils.apply turns a local offset by the pose's yaw."""
    _api, f, ctx = scene
    zone = ctx.world.objects_by_id[1].name
    ns = run_code(
        "rot = get_obj_rot(zone)\n"
        "euler = utils.quatXYZW_to_eulerXYZ(rot)\n"
        "back = utils.eulerXYZ_to_quatXYZW(euler)\n"
        "edge = utils.apply((get_obj_pos(zone), rot), (0.06, 0, 0))\n",
        {**f, "zone": zone})
    assert np.allclose(ns["euler"], f["get_obj_pos_dict"]()[zone][1], atol=1e-9)
    assert ns["euler"][2] == pytest.approx(ZONE_YAW, abs=1e-3)
    assert np.allclose(ns["back"], ns["rot"], atol=1e-9) or np.allclose(ns["back"], -np.array(ns["rot"]), atol=1e-9)
    c = f["get_obj_pos"](zone)
    expected = [c[0] + 0.06 * math.cos(ZONE_YAW), c[1] + 0.06 * math.sin(ZONE_YAW), c[2]]
    assert np.allclose(ns["edge"], expected, atol=1e-3)
    with pytest.raises(PlanError, match="must be 3 numbers"):
        run_code("utils.apply(((0.5, 0.0), (0, 0, 0, 1)), (0.1, 0, 0))", f)


def test_cliport_utils_import_line_is_dropped(scene):
    _api, f, _ctx = scene
    session = LMPSession(complete=lambda *a, **k: None, api=f, objects_text=lambda: "objects = []")
    code = session.prepare("from cliport.utils import utils\nq = utils.eulerXYZ_to_quatXYZW((0, 0, 0))\n", f)
    assert code.splitlines()[0].startswith("pass  # removed: ")
    assert run_code(code, f)["q"] == (0.0, 0.0, 0.0, 1.0)


def test_object_positions_accepts_near_miss_keys(scene):
    _api, f, ctx = scene
    env = reporter_env(f, ctx.world.objects, "put the purple block in the yellow bowl")
    ns = run_code("p = object_positions['purple block with obj_id 5'][0]\n"
                  "q = object_positions['movable small purple block with obj_id 5'][0]\n"
                  "has = 'purple block with obj_id 5' in object_positions\n", env)
    assert ns["p"] == ns["q"] and ns["has"] is False  # reading resolves; the keys stay capmj's names
    with pytest.raises(PlanError, match="KeyError"):
        run_code("object_positions['orange block']", env)
    with pytest.raises(PlanError, match="obj_ids count from 1"):
        run_code("object_positions['red block with obj_id 0']", env)


def test_plan_code_asks_parse_question_through_the_lmp():
    """parse_question is a helper LMP like parse_obj_name: the plan (and helper code below the
    nesting limit) calls it, its prompt's code runs in the sandbox and ret_val is the answer."""
    from prompt_examples import ExampleLLM, build_context, examples, session_for

    example = dict((ex.id, ex) for _, ex in examples("parse_question"))["block_in_zone"]
    ctx = build_context(example)
    llm = ExampleLLM()
    session, _ = session_for(ctx, llm)
    env = session.plan_env()
    ns = run_code("answer = parse_question('is the green block in the blue zone?')\n", env)
    assert ns["answer"] is True
    assert [lmp for lmp, _ in llm.asked] == ["parse_question"]
    assert "parse_question" in session.helper_env()
    session.max_helper_depth = 0
    assert "parse_question" not in session.helper_env()


def test_a_porting_difference_is_labelled_as_the_value_error_it_was():
    """Picking a fixed object was a ValueError (api_misuse for a plan without attempt facts); as a
    PortingDifference it keeps that label."""
    from capmj.bench.failures import _error_label

    assert _error_label("PortingDifference", None) == _error_label("ValueError", None) == "api_misuse"


def test_get_bbox_of_a_list_is_its_first_objects_world_box(scene):
    """CapRavens' get_bbox took the first name of a list; capmj does too, and gives the world box
    (xmin, ymin, zmin, xmax, ymax, zmax), not the original's sizes."""
    _api, f, ctx = scene
    red, purple = ctx.world.objects_by_id[2].name, ctx.world.objects_by_id[5].name
    first = f["get_bbox"]([purple, red])
    assert first == f["get_bbox"](purple) and len(first) == 6
    x, y, z = f["get_obj_pos"](purple)
    assert first[0] < x < first[3] and first[1] < y < first[4] and first[2] < z < first[5]
    assert 0.04 <= first[5] - first[2] < 0.045  # a small block's height, read as zmax - zmin
    assert f["get_bbox"]((red,)) == f["get_bbox"](red)
    with pytest.raises(ValueError, match="a list gives its first object's box"):
        f["get_bbox"]([])
