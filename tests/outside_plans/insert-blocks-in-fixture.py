# Goal: "Each L-shaped fixture can hold three blocks, ... the three places that can hold blocks are
# [(0,0,0),(a,0,0),(0,a,0)] in the fixture's local coordinate system ... Fill in all the fixtures
# ... three blocks with different colors."
# The fixture's local frame: origin get_obj_pos(fixture), axes turned by get_obj_rot(fixture).
# Each block is placed at its slot turned like the fixture. Colours: each fixture takes one block
# of each of the three colours with the most blocks left (this always finds a fill when one exists).
fixtures = [n for n in objects if ' fixture ' in n]
blocks = [n for n in objects if ' block ' in n]
a = 0.04
left = {}
for b in blocks:
    left.setdefault(get_color(b), []).append(b)
for fixture in fixtures:
    colors = sorted(left, key=lambda c: len(left[c]), reverse=True)[:3]
    chosen = [left[c].pop(0) for c in colors]
    left = {c: v for c, v in left.items() if v}
    ox, oy, _ = get_obj_pos(fixture)
    q = get_obj_rot(fixture)
    yaw = 2 * math.atan2(q[2], q[3])
    c, s = math.cos(yaw), math.sin(yaw)
    for block, (u, v) in zip(chosen, [(0, 0), (a, 0), (0, a)]):
        put_first_on_second(block, ([ox + c * u - s * v, oy + s * u + c * v, a / 2], q))
