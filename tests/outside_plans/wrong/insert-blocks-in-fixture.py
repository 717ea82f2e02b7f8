# WRONG PLAN (kept as a negative case): takes the fixture's local origin to be the middle of its
# bounding box instead of get_obj_pos (the prompt says a fixture's get_obj_pos is the origin of its
# local frame, the centre of slot (0, 0, 0)); the blocks land 2-4 cm from the stated slots.
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
    xmin, ymin, _, xmax, ymax, _ = get_bbox(fixture)
    ox, oy = (xmin + xmax) / 2, (ymin + ymax) / 2
    q = get_obj_rot(fixture)
    yaw = 2 * math.atan2(q[2], q[3])
    c, s = math.cos(yaw), math.sin(yaw)
    for block, (u, v) in zip(chosen, [(0, 0), (a, 0), (0, a)]):
        put_first_on_second(block, ([ox + c * u - s * v, oy + s * u + c * v], q))
