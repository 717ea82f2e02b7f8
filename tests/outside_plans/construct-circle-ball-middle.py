# Goal: "Construct a circle with suitable radius with alternating {c1} and {c2} blocks around the ball."
# The ball (r 0.03) is the centre; blocks alternate around it, clear of the ball and of each other.
ball = [n for n in objects if ' ball ' in n][0]
blocks = [n for n in objects if ' block ' in n]
colors = []
for b in blocks:
    if get_color(b) not in colors:
        colors.append(get_color(b))
a = [b for b in blocks if get_color(b) == colors[0]]
b2 = [b for b in blocks if get_color(b) == colors[1]]
order = [x for pair in zip(a, b2) for x in pair]
cx, cy, _ = get_obj_pos(ball)
n = len(order)
radius = max(0.09, 0.065 / (2 * math.sin(math.pi / n)))
points = [[cx + radius * math.cos(2 * math.pi * i / n), cy + radius * math.sin(2 * math.pi * i / n)] for i in range(n)]
for p in points:
    for name in is_target_occupied(p, 0.03):
        if ' block ' in name:
            put_first_on_second(name, get_random_free_pos(targ=points + [ball]))
for block, p in zip(order, points):
    put_first_on_second(block, p)
