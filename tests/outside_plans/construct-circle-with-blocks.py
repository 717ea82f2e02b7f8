# Goal: "Construct a circle with suitable radius with alternating {c1} and {c2} blocks in the zone."
# Alternate the two colours around a circle at the zone's centre; pick the radius so that
# neighbours are >= 6 cm apart (no touching) but the circle stays inside the zone. get_bbox of a
# turned zone is its world-aligned box, so the side is the box width / (|cos yaw| + |sin yaw|).
zone = [n for n in objects if ' zone ' in n][0]
blocks = [n for n in objects if ' block ' in n]
colors = []
for b in blocks:
    if get_color(b) not in colors:
        colors.append(get_color(b))
groups = [[b for b in blocks if get_color(b) == c] for c in colors]
order = []
while any(groups):
    for g in groups:
        if g:
            order.append(g.pop(0))
cx, cy, _ = get_obj_pos(zone)
q = get_obj_rot(zone)
yaw = 2 * math.atan2(q[2], q[3])
xmin, ymin, _, xmax, ymax, _ = get_bbox(zone)
side = (xmax - xmin) / (abs(math.cos(yaw)) + abs(math.sin(yaw)))
n = len(order)
radius = max(0.06, 0.06 / (2 * math.sin(math.pi / n)))
radius = min(radius, side / 2 - 0.01)
points = [[cx + radius * math.cos(2 * math.pi * i / n), cy + radius * math.sin(2 * math.pi * i / n)] for i in range(n)]
# blocks that already lie where the circle goes would be stacked on: move them away first
for p in points:
    for name in is_target_occupied(p, 0.03):
        if ' block ' in name:
            put_first_on_second(name, get_random_free_pos(targ=points + [zone]))
for block, p in zip(order, points):
    put_first_on_second(block, p)
