# Goal: "Construct a circle with suitable radius with alternating {c1} and {c2} blocks around the ball."
# As a circle in a zone, but centred on the ball and wide enough that every block (turned to face
# the centre) keeps 3 cm between its inner face and the ball.
words = goal.rstrip('.').split()
c1, c2 = words[words.index('alternating') + 1], words[words.index('alternating') + 3]
ball = [name for name in objects if ' ball ' in name][0]
first = [name for name in objects if ' block ' in name and get_color(name) == c1]
second = [name for name in objects if ' block ' in name and get_color(name) == c2]
n = len(first) + len(second)
bbox = get_bbox(first[0])
size = bbox[5] - bbox[2]
ball_box = get_bbox(ball)
ball_radius = (ball_box[3] - ball_box[0]) / 2
a = math.pi / n
radius = max(ball_radius + size / 2 + 0.03, (size * (math.cos(a) + math.sin(a)) + 0.01) / (2 * math.sin(a)))
cx, cy, _ = get_obj_pos(ball)
for k in range(n):
    block = first.pop(0) if k % 2 == 0 else second.pop(0)
    angle = 2 * math.pi * k / n
    pos = [cx + radius * math.cos(angle), cy + radius * math.sin(angle), size / 2]
    put_first_on_second(block, (pos, [0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2)]))
