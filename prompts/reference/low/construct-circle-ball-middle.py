# Goal: "... a circle of blocks alternating {c1} and {c2} ... with the ball in the middle": the
# blocks evenly around the ball, clear of it, 1 cm between neighbours, turned to face the centre.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
words = goal.rstrip('.').split()
c1, c2 = words[words.index('alternating') + 1], words[words.index('alternating') + 3]
ball = obj([name for name in objects if ' ball ' in name][0])
first = [name for name in objects if ' block ' in name and obj(name)['color'] == c1]
second = [name for name in objects if ' block ' in name and obj(name)['color'] == c2]
n = len(first) + len(second)
size = 2 * obj(first[0])['half_size'][2]
ball_radius = (ball['bbox'][3] - ball['bbox'][0]) / 2
a = math.pi / n
radius = max(ball_radius + size / 2 + 0.03, (size * (math.cos(a) + math.sin(a)) + 0.01) / (2 * math.sin(a)))
cx, cy, _ = ball['position']
for k in range(n):
    block = first.pop(0) if k % 2 == 0 else second.pop(0)
    angle = 2 * math.pi * k / n
    put(block, cx + radius * math.cos(angle), cy + radius * math.sin(angle), angle)
