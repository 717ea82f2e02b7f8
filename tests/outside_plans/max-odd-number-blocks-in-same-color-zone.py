# Goal: "Place the maximal odd number of blocks of the same color in each correspondingly colored zone."
# For each zone: the largest odd number <= the count of its colour's blocks, laid out flat on a
# 3 x 3 grid turned like the zone (pose targets); every other block is taken out of the zones first.
zones = [n for n in objects if ' zone ' in n]
blocks = [n for n in objects if ' block ' in n]
plan = {}
for zone in zones:
    same = [b for b in blocks if get_color(b) == get_color(zone)]
    m = len(same) if len(same) % 2 == 1 else len(same) - 1
    plan[zone] = same[:max(m, 0)]
keep = [b for zone in zones for b in plan[zone]]
for zone in zones:
    for name in sorted([n for n in is_target_occupied(zone) if ' block ' in n], key=lambda n: get_obj_pos(n)[2], reverse=True):
        if name not in keep:
            put_first_on_second(name, get_random_free_pos(targ=zones))
for zone in zones:
    cx, cy, _ = get_obj_pos(zone)
    q = get_obj_rot(zone)
    yaw = 2 * math.atan2(q[2], q[3])
    c, s = math.cos(yaw), math.sin(yaw)
    cells = [(u, v) for u in (-0.042, 0.0, 0.042) for v in (-0.042, 0.0, 0.042)]
    cells.sort(key=lambda uv: abs(uv[0]) + abs(uv[1]))  # centre first
    for block, (u, v) in zip(plan[zone], cells):
        put_first_on_second(block, ([cx + c * u - s * v, cy + s * u + c * v, 0.02], q))
