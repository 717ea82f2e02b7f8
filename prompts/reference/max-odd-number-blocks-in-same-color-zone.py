# Goal: "Place the maximal odd number of blocks of the same color in each correspondingly colored zone."
# For every zone: of the blocks of its colour, put the largest odd number (all of them when the
# count is odd, one fewer when it is even) into the zone, side by side on a 2 x 3 grid of spots
# 0.05 m apart in the zone's own frame, turned like the zone; the leftover block stays put.
SPOTS = [(u, v) for v in (0.0, -0.05, 0.05) for u in (-0.025, 0.025)]
zones = [name for name in objects if ' zone ' in name]
blocks = [name for name in objects if ' block ' in name]
for zone in zones:
    colour = get_color(zone)
    mine = [block for block in blocks if get_color(block) == colour]
    count = len(mine) if len(mine) % 2 == 1 else len(mine) - 1
    x, y, _ = get_obj_pos(zone)
    quat = get_obj_rot(zone)  # (x, y, z, w)
    yaw = math.atan2(2 * (quat[3] * quat[2] + quat[0] * quat[1]), 1 - 2 * (quat[1] ** 2 + quat[2] ** 2))
    c, s = math.cos(yaw), math.sin(yaw)
    for block, (u, v) in zip(mine[:count], SPOTS):
        put_first_on_second(block, ([x + c * u - s * v, y + s * u + c * v], quat))
