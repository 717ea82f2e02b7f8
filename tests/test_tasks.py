"""Tests of the registered tasks: scene generation, goal text, oracle goals and predicates.

The generic tests iterate over every task the registry knows (A–J and the generated tasks, and
whatever else is installed through the ``capmj.tasks`` entry points); the near-miss tests below
are specific to A–J (the generated tasks have theirs in ``test_generated_tasks.py``).

No physics: solutions are built by hand from the oracle goals (every object at its target), near
misses by moving single objects of such a solution.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from capmj.sim.objects import BOWL_HEIGHT, ZONE_SIZE
from capmj.sim.palette import COLOR_NAMES, COOL, WARM
from capmj.sim.state import Pose, SceneState
from capmj.tasks import predicates as P
from capmj.tasks.builtin import BENCHMARK_TASKS
from capmj.tasks.protocol import Scene, Task, make_scene
from capmj.tasks.registry import get_task, resolve
from capmj_tasks import (
    move_blocks_between_absolute_positions as F,
    move_blocks_between_absolute_positions_by_size as G,
    put_block_into_matching_bowl as H,
    put_block_into_mismatching_bowl as I,
    stack_all_blocks_on_a_zone as A,
    stack_blocks_by_color_and_size as D,
    stack_blocks_by_relative_position_and_color as E,
    stack_blocks_of_same_color as C,
    stack_blocks_of_same_size as B,
    stack_blocks_with_alternate_color as J,
)
from capmj_tasks.common import solved_state

ALL = resolve("all")
"""Every registered task: the generic tests run over all of them."""
TASKS = {name: get_task(name) for name in ALL}
SPEC_NAMES = list(BENCHMARK_TASKS)
STACK_TASKS = [A.TASK.name, B.TASK.name, C.TASK.name, D.TASK.name, E.TASK.name, J.TASK.name]
N_SEEDS = 1000
FIXED_GOAL_TEXT = {
    C.TASK.name, H.TASK.name, I.TASK.name, "build-rectangular-pyramid", "build-cube",
    "max-odd-number-blocks-in-same-color-zone", "stack-most-color-block", "zone-bisector", "insert-blocks-in-fixture",
}
"""Tasks whose goal text has no placeholder (the spec's wording), so it is the same for every seed."""
SOLVE_SEEDS = list(range(10001, 10041, 2))  # the test split's first 20 seeds


def test_registry_names_and_protocol():
    assert set(SPEC_NAMES) <= set(TASKS)
    assert sorted(resolve("benchmark")) == sorted(SPEC_NAMES)
    for t in TASKS.values():
        assert isinstance(t, Task)
        assert t.tags & {"benchmark", "extended"}, t.name
        assert (t.name in SPEC_NAMES) == ("benchmark" in t.tags)
        doc = type(t).__doc__ or ""
        for part in ("Task Description:", "Randomizations:", "Success Conditions:"):
            assert part in doc, (t.name, part)


# --------------------------------------------------------------------------------------- scenes
@pytest.mark.parametrize("name", ALL)
def test_same_seed_same_scene_different_seed_different_scene(name):
    t = TASKS[name]
    a, b = make_scene(t, 10001), make_scene(t, 10001)
    assert a == b and a.goal == b.goal
    scenes = [make_scene(t, s) for s in range(10001, 10021)]
    assert len({tuple(o.pos for o in s.objects) for s in scenes}) == len(scenes)
    assert len({s.goal for s in scenes}) > 1 or name in FIXED_GOAL_TEXT


def _word_in(word: str, text: str) -> bool:
    return re.search(rf"\b{re.escape(word)}\b", text) is not None


def check_goal_words(scene: Scene) -> None:
    """Every colour / size / temperature word of the goal text exists in the scene."""
    text = scene.goal
    colours = {o.color for o in scene.objects}
    for c in COLOR_NAMES:
        if _word_in(c, text):
            assert c in colours, (c, text)
    for c, kind in re.findall(r"\b(\w+) (zone|block|bowl)\b", text):
        if c in COLOR_NAMES:
            assert any(o.color == c and o.kind == kind for o in scene.objects), (c, kind, text)
    blocks = [o for o in scene.objects if o.kind == "block"]
    if _word_in("bigger", text):
        assert any(b.size == "big" for b in blocks)
    if _word_in("smaller", text):
        assert any(b.size == "small" for b in blocks)
    if _word_in("warm", text):
        assert any(b.color in WARM for b in blocks)
    if _word_in("cool", text):
        assert any(b.color in COOL for b in blocks)


def footprint_radius(o) -> float:
    """A circle around the object's position containing its footprint at any yaw (an L-fixture's
    origin is a slot centre, not the middle of its box, so its circle is ``P.FIXTURE_RADIUS``)."""
    return P.FIXTURE_RADIUS if o.kind == "fixture" else o.footprint_radius


def footprint_extent(o) -> tuple[float, float]:
    """Half sizes (m) of the footprint's axis-aligned box at the object's yaw (squares turned,
    everything else its circle)."""
    if o.kind in ("block", "zone"):
        hx, hy, _ = o.half_extents
        c, s = abs(math.cos(o.yaw)), abs(math.sin(o.yaw))
        return hx * c + hy * s, hx * s + hy * c
    r = footprint_radius(o)
    return r, r


def check_layout(scene: Scene) -> None:
    objs = scene.objects
    ids = [o.obj_id for o in objs]
    assert ids == list(range(1, len(objs) + 1))
    xy = np.array([o.pos[:2] for o in objs])
    r = np.array([footprint_radius(o) for o in objs])
    d = np.hypot(xy[:, None, 0] - xy[None, :, 0], xy[:, None, 1] - xy[None, :, 1])
    np.fill_diagonal(d, np.inf)
    assert np.all(d >= r[:, None] + r[None, :]), "footprints overlap"
    ext = np.array([footprint_extent(o) for o in objs])
    assert np.all(xy[:, 0] - ext[:, 0] >= 0.25 - 1e-9) and np.all(xy[:, 0] + ext[:, 0] <= 0.75 + 1e-9)
    assert np.all(xy[:, 1] - ext[:, 1] >= -0.5 - 1e-9) and np.all(xy[:, 1] + ext[:, 1] <= 0.5 + 1e-9)
    for o in objs:
        assert o.pos[2] == pytest.approx(o.height / 2)
    zones = [o.color for o in objs if o.kind == "zone"]
    assert len(set(zones)) == len(zones), "two zones share a colour"
    json.dumps(dict(scene.info))


TASK_FACTS: dict = {}
"""Task-specific scene checks by task name (``scene -> None``, asserting); other test modules
add theirs with :func:`task_facts`."""


def task_facts(name: str):
    def register(fn):
        TASK_FACTS[name] = fn
        return fn
    return register


def check_task_facts(name: str, scene: Scene) -> None:
    if name in TASK_FACTS:
        TASK_FACTS[name](scene)
        return
    info = scene.info
    by = {o.obj_id: o for o in scene.objects}
    blocks = [o for o in scene.objects if o.kind == "block"]
    if name == A.TASK.name:
        assert 2 <= len(blocks) <= 5 and len({b.color for b in blocks}) == len(blocks)
        assert sorted(info["blocks"]) == [b.obj_id for b in blocks]
    elif name == B.TASK.name:
        assert 1 <= len(info["big"]) <= 4 and 1 <= len(info["small"]) <= 4
        assert all(by[i].size == "big" for i in info["big"]) and all(by[i].size == "small" for i in info["small"])
        assert len(info["zones"]) == 2
    elif name == C.TASK.name:
        zone_cols = {o.color for o in scene.objects if o.kind == "zone"}
        for g in info["groups"]:
            assert 2 <= len(g["blocks"]) <= 3 and by[g["zone"]].color == g["color"]
            assert sorted(g["blocks"]) == sorted(b.obj_id for b in blocks if b.color == g["color"])
        assert all(by[i].color not in zone_cols for i in info["distractor_blocks"])
        assert all(by[z].color not in {b.color for b in blocks} for z in info["distractor_zones"])
    elif name == D.TASK.name:
        group = WARM if info["temperature"] == "warm" else COOL
        sel = [b.obj_id for b in blocks if b.size == info["size"] and b.color in group]
        assert sel == info["selected"]
        assert 2 <= len(sel) <= len(blocks) - 1 and 4 <= len(blocks) <= 7
        assert {b.size for b in blocks} == {"big", "small"}
        assert sum(by[i].height for i in sel) <= 0.25
    elif name == E.TASK.name:
        ref = by[info["reference"]]
        d = {b.obj_id: E.signed_distance(info["direction"], b.pos, ref.pos) for b in blocks if b is not ref}
        sel = sorted(i for i, v in d.items() if v > 0.05)
        assert sel == sorted(info["selected"])
        assert 2 <= len(sel) <= 5 and len(sel) <= len(blocks) - 1
        assert all(abs(v - 0.05) >= 0.01 for v in d.values())
        assert sum(1 for b in blocks if b.color == ref.color) == 1
        assert len({b.color for b in blocks}) == len(blocks)
    elif name in (F.TASK.name, G.TASK.name):
        a1, a2 = info["area1"], info["area2"]
        assert a1 != a2
        in1 = [b.obj_id for b in blocks if P.in_area(b.pos, a1)]
        assert sorted(in1) == sorted(info["in_area1"]) and 3 <= len(in1) <= 4
        assert not any(P.in_area(b.pos, a2) for b in blocks)
        assert len(blocks) > len(in1)
        if name == G.TASK.name:
            assert {by[i].size for i in in1} == {"big", "small"}
            assert sorted(info["selected"]) == sorted(i for i in in1 if by[i].size == info["size"])
        else:
            assert sorted(info["selected"]) == sorted(in1)
    elif name == H.TASK.name:
        bowls = [o for o in scene.objects if o.kind == "bowl"]
        assert len({w.color for w in bowls}) == len(bowls)
        for b, w in info["pairs"]:
            assert by[b].color == by[w].color
        assert len({w for _, w in info["pairs"]}) == len(info["pairs"]) >= 2
        assert len(info["distractor_blocks"]) + len(info["distractor_bowls"]) >= 1
    elif name == I.TASK.name:
        bowls = [o for o in scene.objects if o.kind == "bowl"]
        assert len({w.color for w in bowls}) == len(bowls)
        assert len(info["distractor_bowls"]) <= 3
        pairs = info["assignment"]
        assert sorted(b for b, _ in pairs) == sorted(info["blocks"])
        assert len({w for _, w in pairs}) == len(pairs)
        assert all(by[b].color != by[w].color for b, w in pairs)
    elif name == J.TASK.name:
        c2, c3 = info["start_color"], info["other_color"]
        n2 = sum(b.color == c2 for b in blocks)
        n3 = sum(b.color == c3 for b in blocks)
        assert n2 + n3 == len(blocks) and n2 - n3 in (0, 1) and 2 <= len(blocks) <= 5


# ------------------------------------------------------------------------- generated tasks 6–10
def _no_block_in_a_zone(scene: Scene) -> None:
    state = SceneState.from_specs(scene.objects)
    for z in (o for o in scene.objects if o.kind == "zone"):
        assert not P.objects_in_zone(state, z.obj_id), "a block starts in a zone"


@task_facts("divide-blocks")
def _divide_blocks_facts(scene: Scene) -> None:
    info, blocks = scene.info, [o for o in scene.objects if o.kind == "block"]
    k = int(re.search(r"groups of (\d+)", scene.goal).group(1))
    assert k == info["k"] in (2, 3) and 7 <= len(blocks) <= 8 and len({b.color for b in blocks}) == len(blocks)
    assert len(info["zones"]) == math.ceil(len(blocks) / k) == len(info["group_sizes"])
    assert sum(info["group_sizes"]) == len(blocks)
    _no_block_in_a_zone(scene)


@task_facts("max-odd-number-blocks-in-same-color-zone")
def _max_odd_facts(scene: Scene) -> None:
    blocks = [o for o in scene.objects if o.kind == "block"]
    zones = [o for o in scene.objects if o.kind == "zone"]
    counts = {z.color: sum(b.color == z.color for b in blocks) for z in zones}
    assert len(zones) == 3 and {b.color for b in blocks} == set(counts) and 7 <= len(blocks) <= 14
    assert all(1 <= c <= 6 for c in counts.values()) and any(c % 2 == 0 for c in counts.values())
    assert scene.info["targets"] == {c: (n if n % 2 else n - 1) for c, n in counts.items()}
    _no_block_in_a_zone(scene)


@task_facts("stack-most-color-block")
def _stack_most_facts(scene: Scene) -> None:
    blocks = [o for o in scene.objects if o.kind == "block"]
    counts = sorted(((sum(b.color == c for b in blocks), c) for c in {b.color for b in blocks}), reverse=True)
    assert 10 <= len(blocks) <= 15 and 3 <= len(counts) <= 5
    assert counts[0][0] > counts[1][0] and counts[0][1] == scene.info["color"] and counts[0][0] <= 6
    assert sorted(scene.info["selected"]) == sorted(b.obj_id for b in blocks if b.color == counts[0][1])
    _no_block_in_a_zone(scene)


@task_facts("zone-bisector")
def _bisector_facts(scene: Scene) -> None:
    from capmj_tasks.zone_bisector import row_geometry, row_slots

    z1, z2 = (scene.by_id(i) for i in scene.info["zones"])
    blocks = [o for o in scene.objects if o.kind == "block"]
    assert 4 <= len(blocks) <= 6
    mid, e = row_geometry(z1.pos, z2.pos)
    # mirrored: the two zones' yaws are reflections about the bisector (squares: modulo 90°)
    phi = math.atan2(e[1], e[0])
    assert ((z1.yaw + z2.yaw - 2 * phi + math.pi / 4) % (math.pi / 2)) - math.pi / 4 == pytest.approx(0.0, abs=1e-9)
    slots = row_slots(mid, e, len(blocks))
    assert np.all((slots[:, 0] >= 0.3) & (slots[:, 0] <= 0.7) & (np.abs(slots[:, 1]) <= 0.4))
    for o in scene.objects:  # the row's spots are free at reset
        d = np.hypot(slots[:, 0] - o.pos[0], slots[:, 1] - o.pos[1])
        assert np.all(d >= o.footprint_radius + blocks[0].footprint_radius), o


@task_facts("insert-blocks-in-fixture")
def _fixture_facts(scene: Scene) -> None:
    from capmj_tasks.insert_blocks_in_fixture import fill_plan

    fixtures = [o for o in scene.objects if o.kind == "fixture"]
    blocks = [o for o in scene.objects if o.kind == "block"]
    assert 2 <= len(fixtures) <= 4 and len(blocks) == 3 * len(fixtures)
    assert all(b.size == "small" for b in blocks) and len({f.color for f in fixtures}) == 1
    assert fixtures[0].color not in {b.color for b in blocks}
    assert max(sum(b.color == c for b in blocks) for c in {b.color for b in blocks}) <= len(fixtures)
    assert len(fill_plan([b.color for b in blocks], len(fixtures))) == len(fixtures)
    for fill in scene.info["fill"]:
        assert len({scene.by_id(i).color for i in fill}) == 3


@pytest.mark.parametrize("name", ALL)
def test_many_seeds_generate_valid_scenes(name):
    """1000 seeds: text and scene agree, footprints fit the workspace and do not overlap, and the
    initial state is not already a success."""
    t = TASKS[name]
    for seed in range(N_SEEDS):
        scene = make_scene(t, seed)
        check_layout(scene)
        check_goal_words(scene)
        check_task_facts(name, scene)
        v0 = t.evaluate(scene, SceneState.from_specs(scene.objects))
        assert not v0.success and 0.0 <= v0.progress < 1.0 and v0.diagnostics, (seed, v0)


# --------------------------------------------------------------------------------------- helpers
def set_pos(state: SceneState, obj_id: int, pos, quat=None) -> SceneState:
    p = dict(state.poses)
    p[obj_id] = Pose(tuple(float(v) for v in pos), quat if quat is not None else p[obj_id].quat)
    return SceneState(state.objects, p)


def tilt(state: SceneState, obj_id: int, deg: float = 30.0) -> SceneState:
    a = math.radians(deg)
    return set_pos(state, obj_id, state.pos(obj_id), (math.cos(a / 2), math.sin(a / 2), 0.0, 0.0))


def zone_point(state: SceneState, zone_id: int, u: float, v: float) -> np.ndarray:
    """World xy of local zone coordinates (u, v)."""
    c = state.pos(zone_id)[:2]
    yaw = state.poses[zone_id].yaw
    return c + np.array([math.cos(yaw) * u - math.sin(yaw) * v, math.sin(yaw) * u + math.cos(yaw) * v])


def stacks_of(scene: Scene, goals) -> list[tuple[int, list[int]]]:
    """(zone id, block ids bottom to top) of every stack the oracle builds."""
    zones = [o for o in scene.objects if o.kind == "zone"]
    out: dict[int, list[int]] = {}
    for g in goals:
        t = g.targets[0].pos
        z = next(z.obj_id for z in zones if math.hypot(z.pos[0] - t[0], z.pos[1] - t[1]) < 1e-9)
        out.setdefault(z, []).append(g.objects[0])
    return list(out.items())


def move_stack(state: SceneState, ids: list[int], xy) -> SceneState:
    for i in ids:
        p = state.pos(i)
        state = set_pos(state, i, (xy[0], xy[1], p[2]))
    return state


def rebuild_tower(state: SceneState, ids: list[int], xy) -> SceneState:
    z = 0.0
    for i in ids:
        h = state.spec(i).height
        state = set_pos(state, i, (xy[0], xy[1], z + h / 2))
        z += h
    return state


def solved(name: str, seed: int):
    t = TASKS[name]
    scene = make_scene(t, seed)
    goals = t.oracle_goals(scene)
    return t, scene, goals, solved_state(scene, goals)


def assert_rejects(t, scene, state, what: str):
    v = t.evaluate(scene, state)
    assert not v.success, f"{t.name}: {what} was accepted"
    assert 0.0 <= v.progress < 1.0
    assert v.diagnostics, "a failure must say why"
    return v


# --------------------------------------------------------------------------------------- solutions
@pytest.mark.parametrize("name", ALL)
def test_exact_solution_is_accepted(name):
    for seed in SOLVE_SEEDS:
        t, scene, goals, state = solved(name, seed)
        v = t.evaluate(scene, state)
        assert v.success, (seed, v.diagnostics)
        assert v.progress == 1.0
        assert P.ravens_reward(goals, state) == pytest.approx(1.0)
        start = SceneState.from_specs(scene.objects)
        v0 = t.evaluate(scene, start)
        assert not v0.success and v0.progress < 1.0
        assert P.ravens_reward(goals, start) < 1.0
        # the oracle's targets stay reachable and above the table
        for g in goals:
            for tg in g.targets:
                assert 0.25 <= tg.pos[0] <= 0.75 and -0.5 <= tg.pos[1] <= 0.5 and 0 < tg.pos[2] <= 0.3


@pytest.mark.parametrize("name", STACK_TASKS)
def test_stack_near_misses_are_rejected(name):
    for seed in SOLVE_SEEDS:
        t, scene, goals, state = solved(name, seed)
        stacks = stacks_of(scene, goals)
        zone, ids = stacks[0]
        half = ZONE_SIZE * scene.by_id(zone).scale / 2

        # toppled tower: the top block tilted 30°
        assert_rejects(t, scene, tilt(state, ids[-1]), "a tilted block")

        # the whole tower just outside the zone edge, and just inside (accepted)
        assert_rejects(t, scene, move_stack(state, ids, zone_point(state, zone, half + 0.003, 0.0)), "zone edge")
        inside = move_stack(state, ids, zone_point(state, zone, half - 0.003, 0.0))
        assert t.evaluate(scene, inside).success, "a tower just inside the zone edge must count"

        # one block missing: the top block back at its spawn pose
        miss = set_pos(state, ids[-1], scene.by_id(ids[-1]).pos)
        assert_rejects(t, scene, miss, "a missing block")
        assert P.ravens_reward(goals, miss) < 1.0

        # split tower: the upper half rebuilt as a second tower inside the same zone
        if len(ids) >= 2:
            k = len(ids) // 2
            split = rebuild_tower(state, ids[k:], zone_point(state, zone, 0.035, 0.035))
            assert all(P.in_zone(split, i, zone) for i in ids)
            v = assert_rejects(t, scene, split, "a split tower")
            assert v.progress > 0

        # an extra block beside the tower in the zone
        extra = extra_block_for(name, scene)
        if extra is not None:
            xy = zone_point(state, zone, 0.0, 0.045)
            assert_rejects(t, scene, set_pos(state, extra, (xy[0], xy[1], scene.by_id(extra).height / 2)),
                           "an extra block in the zone")


def extra_block_for(name: str, scene: Scene) -> int | None:
    info = scene.info
    if name in (D.TASK.name, E.TASK.name):
        return next(i for i in info["blocks"] if i not in info["selected"])
    if name == C.TASK.name:
        return info["distractor_blocks"][0] if info["distractor_blocks"] else None
    if name == B.TASK.name:
        return info["small"][0]  # a small block in the big blocks' zone
    return None


def test_stack_all_blocks_extra_block_beside_tower():
    """A: the last block lying beside the tower (in the zone) is not "all blocks stacked"."""
    for seed in SOLVE_SEEDS:
        t, scene, goals, state = solved(A.TASK.name, seed)
        zone = scene.info["zone"]
        top = goals[-1].objects[0]
        xy = zone_point(state, zone, 0.0, 0.045)
        beside = set_pos(state, top, (xy[0], xy[1], 0.02))
        assert P.in_zone(beside, top, zone)
        assert_rejects(t, scene, beside, "a block beside the tower")


def test_same_size_either_assignment_and_mixed_stacks():
    t = B.TASK
    for seed in SOLVE_SEEDS:
        _, scene, goals, state = solved(t.name, seed)
        z1, z2 = scene.info["zones"]
        big, small = scene.info["big"], scene.info["small"]
        swapped = rebuild_tower(state, big, state.pos(z2)[:2])
        swapped = rebuild_tower(swapped, small, state.pos(z1)[:2])
        assert t.evaluate(scene, swapped).success
        # both stacks in the same zone is not the task
        both = rebuild_tower(state, small, zone_point(state, z1, 0.0, 0.045))
        assert_rejects(t, scene, both, "both stacks in one zone")
        # one mixed tower in a zone
        mixed = rebuild_tower(state, [big[0], small[0]], state.pos(z1)[:2])
        assert_rejects(t, scene, mixed, "a mixed-size stack")


def test_alternate_color_wrong_order_rejected():
    t = J.TASK
    for seed in SOLVE_SEEDS:
        _, scene, goals, state = solved(t.name, seed)
        order = [g.objects[0] for g in goals]
        zone = scene.info["zone"]
        xy = state.pos(zone)[:2]
        wrong = rebuild_tower(state, [order[1], order[0]] + order[2:], xy)  # starts with the other colour
        v = assert_rejects(t, scene, wrong, "a stack starting with the wrong colour")
        assert any("colours bottom to top" in d for d in v.diagnostics)
        c2 = scene.info["start_color"]
        same = [i for i in order if scene.by_id(i).color == c2]
        others = [i for i in order if i not in same]
        if len(same) >= 2:
            grouped = rebuild_tower(state, same + others, xy)  # c2, c2, … : not alternating
            assert_rejects(t, scene, grouped, "two blocks of one colour in a row")
        assert t.evaluate(scene, rebuild_tower(state, order, xy)).success


@pytest.mark.parametrize("name", [F.TASK.name, G.TASK.name])
def test_area_move_near_misses(name):
    for seed in SOLVE_SEEDS:
        t, scene, goals, state = solved(name, seed)
        info = scene.info
        sel = info["selected"]
        start = {int(k): v for k, v in info["start_positions"].items()}
        a2 = P.area_bounds(info["area2"])
        # one selected block left where it was
        left = set_pos(state, sel[0], start[sel[0]])
        assert_rejects(t, scene, left, "a block left in area1")
        assert P.ravens_reward(goals, left) < 1.0
        # one selected block just across the area2 border (x split line at 0.5)
        p = state.pos(sel[0])
        x_out = 0.497 if a2[0] == 0.5 else 0.503
        assert_rejects(t, scene, set_pos(state, sel[0], (x_out, p[1], p[2])), "a block just outside area2")
        x_in = 0.503 if a2[0] == 0.5 else 0.497
        assert t.evaluate(scene, set_pos(state, sel[0], (x_in, p[1], p[2]))).success
        # a block that should stay put nudged by 0.035 m (rejected) or 0.02 m (accepted)
        other = next(i for i in info["blocks"] if i not in sel)
        q = np.asarray(start[other])
        assert_rejects(t, scene, set_pos(state, other, q + (0.035, 0, 0)), "a moved bystander")
        assert t.evaluate(scene, set_pos(state, other, q + (0.02, 0, 0))).success


def test_matching_bowl_near_misses():
    t = H.TASK
    for seed in SOLVE_SEEDS:
        _, scene, goals, state = solved(t.name, seed)
        (b1, w1), (b2, w2) = scene.info["pairs"][:2]
        c = state.pos(w1)
        z = state.pos(b1)[2]
        assert_rejects(t, scene, set_pos(state, b1, (c[0] + 0.052, c[1], z)), "a block beside its bowl")
        assert t.evaluate(scene, set_pos(state, b1, (c[0] + 0.045, c[1], z))).success
        assert_rejects(t, scene, set_pos(state, b1, (c[0], c[1], c[2] + BOWL_HEIGHT / 2 + 0.03)), "a block above")
        swapped = set_pos(set_pos(state, b1, state.pos(b2)), b2, state.pos(b1))
        assert_rejects(t, scene, swapped, "blocks in each other's bowls")
        assert P.ravens_reward(goals, swapped) < 1.0
        for d in scene.info["distractor_blocks"]:
            cw = state.pos(w2)
            in_bowl = set_pos(state, d, (cw[0] + 0.01, cw[1], z))
            assert_rejects(t, scene, in_bowl, "a distractor block in a bowl")


def test_mismatching_bowl_near_misses():
    t = I.TASK
    for seed in SOLVE_SEEDS:
        _, scene, goals, state = solved(t.name, seed)
        by_col = {scene.by_id(w).color: w for w in scene.info["bowls"]}
        b = next(b for b in scene.info["blocks"] if scene.by_id(b).color in by_col)
        own = state.pos(by_col[scene.by_id(b).color])
        z = state.pos(b)[2]
        wrong = set_pos(state, b, (own[0], own[1], z))
        v = assert_rejects(t, scene, wrong, "a block in its own colour's bowl")
        assert any("same colour" in d for d in v.diagnostics)
        miss = set_pos(state, b, scene.by_id(b).pos)
        assert_rejects(t, scene, miss, "a block in no bowl")
        assert P.ravens_reward(goals, miss) < 1.0
        # two blocks sharing a mismatching bowl is still "every block in a mismatching bowl"
        b_other, w_other = scene.info["assignment"][0]
        if b_other != b and scene.by_id(w_other).color != scene.by_id(b).color:
            cw = state.pos(w_other)
            shared = set_pos(state, b, (cw[0] + 0.022, cw[1], z))  # side by side on the floor
            shared = set_pos(shared, b_other, (cw[0] - 0.022, cw[1], z))
            assert t.evaluate(scene, shared).success


def test_progress_grows_with_partial_stacks():
    t = A.TASK
    for seed in SOLVE_SEEDS:
        _, scene, goals, state = solved(t.name, seed)
        ids = [g.objects[0] for g in goals]
        progress = []
        for k in range(len(ids) + 1):
            s = state
            for i in ids[k:]:
                s = set_pos(s, i, scene.by_id(i).pos)
            progress.append(t.evaluate(scene, s).progress)
        assert progress == sorted(progress) and progress[0] == 0.0 and progress[-1] == 1.0
