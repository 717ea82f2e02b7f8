# Goal: "... build a {a}-{b}-{c} rectangular pyramid ... in the zone": square layers of a, b, c
# blocks on the zone centre, turned like the zone, a quarter block apart, bottom layer first.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
words = goal.rstrip('.').split()
layer_counts = [int(k) for k in words[words.index('rectangular') - 1].split('-')]  # "9-4-1"
zone = obj([name for name in objects if ' zone ' in name][0])
blocks = [name for name in objects if ' block ' in name]
size = 2 * obj(blocks[0])['half_size'][2]
pitch = 1.25 * size
cx, cy, _ = zone['position']
yaw = zone['yaw']
for level, count in enumerate(layer_counts):
    side = int(round(math.sqrt(count)))
    for i in range(side):
        for j in range(side):
            u, v = (j - (side - 1) / 2) * pitch, (i - (side - 1) / 2) * pitch
            put(blocks.pop(0), cx + math.cos(yaw) * u - math.sin(yaw) * v, cy + math.sin(yaw) * u + math.cos(yaw) * v, yaw)
