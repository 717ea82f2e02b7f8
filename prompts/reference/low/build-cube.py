# Goal: "... build a {nx}*{ny}*{nz} cube ... in the zone": layers of nx by ny blocks on the zone
# centre, turned like the zone, 1/8 of a block apart, bottom layer first.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
words = goal.rstrip('.').split()
nx, ny, nz = [int(k) for k in words[words.index('cube') - 1].split('*')]  # "2*2*2"
zone = obj([name for name in objects if ' zone ' in name][0])
blocks = [name for name in objects if ' block ' in name]
size = 2 * obj(blocks[0])['half_size'][2]
pitch = 1.125 * size
cx, cy, _ = zone['position']
yaw = zone['yaw']
for level in range(nz):
    for i in range(ny):
        for j in range(nx):
            u, v = (j - (nx - 1) / 2) * pitch, (i - (ny - 1) / 2) * pitch
            put(blocks.pop(0), cx + math.cos(yaw) * u - math.sin(yaw) * v, cy + math.sin(yaw) * u + math.cos(yaw) * v, yaw)
