# Goal: "Construct two concentric circles in the zone using {n} {c1} and {m} {c2} blocks."
# The colour with fewer blocks on the inner circle, the other on the outer one, both around the
# zone centre, blocks evenly spaced and turned to face the centre; 1 cm between neighbours.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
words = goal.rstrip('.').split()
at = words.index('using')
groups = sorted([(int(words[at + 1]), words[at + 2]), (int(words[at + 4]), words[at + 5])])
zone = obj([name for name in objects if ' zone ' in name][0])
cx, cy, _ = zone['position']
phase = zone['yaw']


def ring_radius(count, size):
    a = math.pi / count
    return (size * (math.cos(a) + math.sin(a)) + 0.01) / (2 * math.sin(a))


inner_edge = 0.0
for count, color in groups:
    blocks = [name for name in objects if ' block ' in name and obj(name)['color'] == color]
    size = 2 * obj(blocks[0])['half_size'][2]
    if inner_edge == 0.0:
        radius = max(1.5 * size, ring_radius(len(blocks), size))
    else:
        radius = max(ring_radius(len(blocks), size), inner_edge + 0.01 + size / 2)
    for k, block in enumerate(blocks):
        angle = phase + 2 * math.pi * k / len(blocks)
        put(block, cx + radius * math.cos(angle), cy + radius * math.sin(angle), angle)
    inner_edge = math.hypot(radius + size / 2, size / 2)
