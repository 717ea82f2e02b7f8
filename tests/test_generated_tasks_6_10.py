"""Near misses and exact solutions of the generated tasks 6–10 (hand-built states, no physics).

Each solution is the oracle's ideal final state (every goal object at its target); each near miss
changes one thing the spec's success condition forbids.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from capmj.tasks import predicates as P
from capmj_tasks.zone_bisector import PITCH, row_geometry
from test_tasks import SOLVE_SEEDS, assert_rejects, rebuild_tower, set_pos, solved, stacks_of

SEEDS = SOLVE_SEEDS[:10]


@pytest.mark.parametrize("seed", SEEDS)
def test_divide_blocks_wrong_group_sizes(seed):
    t, scene, goals, state = solved("divide-blocks", seed)
    assert t.evaluate(scene, state).success
    towers = sorted(stacks_of(scene, goals), key=lambda kv: -len(kv[1]))
    (z_big, big), (z_other, other), (_, small) = towers[0], towers[1], towers[-1]
    # the top block of a full group moved onto another full group: one group too small, one too big
    moved = rebuild_tower(state, other + [big[-1]], state.pos(z_other)[:2])
    v = assert_rejects(t, scene, moved, "a stack group of the wrong size")
    assert any("must be" in d for d in v.diagnostics) and v.progress > 0.5
    # two groups side by side in one zone: the zone is not one stack, another zone is empty
    c = state.pos(z_big)[:2]
    two = rebuild_tower(state, small, c + (0.0, 0.045))
    two = rebuild_tower(two, big, c - (0.0, 0.035))
    v = assert_rejects(t, scene, two, "two stacks in one zone")
    assert any("not one stack" in d for d in v.diagnostics)
    assert any("holds no block" in d for d in v.diagnostics)


@pytest.mark.parametrize("seed", SEEDS)
def test_max_odd_even_count_and_foreign_blocks(seed):
    t, scene, goals, state = solved("max-odd-number-blocks-in-same-color-zone", seed)
    assert t.evaluate(scene, state).success
    placed = {g.objects[i] for g in goals for i in range(len(g.objects))}
    zones = {scene.by_id(z).color: z for z in scene.info["zones"]}
    spare = [b for b in scene.info["blocks"] if b not in placed]
    assert spare  # at least one colour has an even count, so one of its blocks stays out
    b = spare[0]
    z = zones[scene.by_id(b).color]
    c = state.pos(z)
    even = set_pos(state, b, (c[0], c[1], 0.06))  # on top of the centre block: an even number in the zone
    v = assert_rejects(t, scene, even, "an even number of blocks in a zone")
    assert any("needs exactly" in d for d in v.diagnostics)
    # a block of another colour in the zone
    other = next((i for i in spare if scene.by_id(i).color != scene.by_id(b).color), None)
    foreign = next(i for i in placed if scene.by_id(i).color != scene.by_id(b).color)
    v = assert_rejects(t, scene, set_pos(state, foreign, (c[0], c[1], 0.06)), "a block in another colour's zone")
    assert any("must not be in" in d for d in v.diagnostics)
    if other is not None:
        assert_rejects(t, scene, set_pos(state, other, (c[0], c[1], 0.06)), "a spare block of another colour")
    # one block short
    g = goals[0]
    assert_rejects(t, scene, set_pos(state, g.objects[0], scene.by_id(g.objects[0]).pos), "a block missing")


@pytest.mark.parametrize("seed", SEEDS)
def test_stack_most_color_minority_stacked(seed):
    t, scene, goals, state = solved("stack-most-color-block", seed)
    assert t.evaluate(scene, state).success
    zone, colour = scene.info["zone"], scene.info["color"]
    blocks = [scene.by_id(i) for i in scene.info["blocks"]]
    counts = {c: sum(b.color == c for b in blocks) for c in {b.color for b in blocks} - {colour}}
    second = max(counts, key=lambda c: (counts[c], c))
    minority = [b.obj_id for b in blocks if b.color == second]
    start = rebuild_tower(state, scene.info["selected"], (0.0, 0.0))  # majority out of the way…
    for i in scene.info["selected"]:
        start = set_pos(start, i, scene.by_id(i).pos)  # …back at their spawn poses
    v = assert_rejects(t, scene, rebuild_tower(start, minority, state.pos(zone)[:2]), "a minority colour stacked")
    assert v.progress < 0.5
    # the majority stack with a minority block on top
    top = rebuild_tower(state, scene.info["selected"] + minority[:1], state.pos(zone)[:2])
    v = assert_rejects(t, scene, top, "a minority block on the majority stack")
    assert any("must not be in" in d for d in v.diagnostics)


@pytest.mark.parametrize("seed", SEEDS)
def test_zone_bisector_row_near_misses(seed):
    t, scene, goals, state = solved("zone-bisector", seed)
    assert t.evaluate(scene, state).success
    z1, z2 = scene.info["zones"]
    mid, e = row_geometry(state.pos(z1), state.pos(z2))
    n = np.array([-e[1], e[0]])
    ids = sorted(scene.info["blocks"], key=lambda i: float((state.pos(i)[:2] - mid) @ e))

    def shifted(st, i, vec):
        p = st.pos(i)
        return set_pos(st, i, (p[0] + vec[0], p[1] + vec[1], p[2]))

    # uneven gaps: the end block 0.02 m farther out
    v = assert_rejects(t, scene, shifted(state, ids[-1], 0.02 * e), "a bisector row with uneven gaps")
    assert any("apart" in d for d in v.diagnostics)
    # a block 0.02 m off the line
    v = assert_rejects(t, scene, shifted(state, ids[1], 0.02 * n), "a block off the bisector")
    assert any("off the bisector" in d for d in v.diagnostics)
    # the whole row slid 0.03 m along the line: even and on the line, but not bisected by the zones' line
    slid = state
    for i in ids:
        slid = shifted(slid, i, 0.03 * e)
    v = assert_rejects(t, scene, slid, "a row off the midpoint")
    assert any("midpoint" in d for d in v.diagnostics)
    # a gap of one block size edge to edge is "near" it: every block jittered 5 mm is accepted
    rng = np.random.default_rng(seed)
    jit = state
    for i in ids:
        jit = shifted(jit, i, rng.uniform(-0.005, 0.005, 2))
    assert t.evaluate(scene, jit).success
    # the row stacked up instead of lying on the table
    p = state.pos(ids[0])
    assert_rejects(t, scene, set_pos(state, ids[0], (p[0], p[1], p[2] + 0.04)), "a block in the air")
    assert PITCH == pytest.approx(0.08)


@pytest.mark.parametrize("seed", SEEDS)
def test_fixture_near_misses(seed):
    t, scene, goals, state = solved("insert-blocks-in-fixture", seed)
    assert t.evaluate(scene, state).success
    fixtures, fill = scene.info["fixtures"], scene.info["fill"]
    f0 = state.spec(fixtures[0])
    xdir = np.array([math.cos(f0.yaw), math.sin(f0.yaw), 0.0])
    b = fill[0][1]  # the block in slot (a,0,0) of the first fixture
    p = state.pos(b)
    # 1.5 cm out of its slot along the fixture's x axis: rejected; 0.5 cm: still in
    v = assert_rejects(t, scene, set_pos(state, b, p + 0.015 * xdir), "a block 1.5 cm out of its slot")
    assert any("slot (a,0,0)" in d and "is empty" in d for d in v.diagnostics)
    assert t.evaluate(scene, set_pos(state, b, p + 0.005 * xdir)).success
    # a block sitting on the wall top above its slot is not in it
    assert_rejects(t, scene, set_pos(state, b, p + (0, 0, 0.04)), "a block above the slot")
    # two blocks of one colour in a fixture: swap a block with a same-coloured block of another fixture
    colour = {i: state.spec(i).color for f in fill for i in f}
    for fa, fb in ((fill[0], f) for f in fill[1:]):
        pair = next(((x, y) for x in fa for y in fb if colour[y] in {colour[i] for i in fa} and colour[x] != colour[y]),
                    None)
        if pair:
            x, y = pair
            swapped = set_pos(set_pos(state, x, state.pos(y)), y, state.pos(x))
            v = assert_rejects(t, scene, swapped, "a fixture with two blocks of one colour")
            assert any(f"holds 2 {colour[y]} blocks" in d for d in v.diagnostics)
            assert v.progress > 0.5
            break
    # a fixture left empty
    empty = state
    for i in fill[-1]:
        empty = set_pos(empty, i, scene.by_id(i).pos)
    assert_rejects(t, scene, empty, "an empty fixture")


def test_fixture_slots_follow_the_fixture_frame():
    """Slots (0,0,0), (a,0,0), (0,a,0) in the fixture frame, at any yaw, at half a block height."""
    s = P.fixture_slots((0.5, 0.1, 0.02), math.pi / 2)
    assert np.allclose(s, [[0.5, 0.1, 0.02], [0.5, 0.14, 0.02], [0.46, 0.1, 0.02]])
