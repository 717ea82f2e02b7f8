# Goal: line the blocks up on the perpendicular bisector of the two zones, centred between them,
# two block sizes apart, turned along the line, each block to the spot in its order along it.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
zones = [name for name in objects if ' zone ' in name]
blocks = [name for name in objects if ' block ' in name]
x1, y1, _ = obj(zones[0])['position']
x2, y2, _ = obj(zones[1])['position']
mx, my = (x1 + x2) / 2, (y1 + y2) / 2
length = math.hypot(x2 - x1, y2 - y1)
ex, ey = -(y2 - y1) / length, (x2 - x1) / length  # along the bisector
pitch = 4 * obj(blocks[0])['half_size'][2]  # two block sizes
yaw = math.atan2(ey, ex)
n = len(blocks)
spots = [(mx + (i - (n - 1) / 2) * pitch * ex, my + (i - (n - 1) / 2) * pitch * ey) for i in range(n)]
along = sorted(blocks, key=lambda b: (obj(b)['position'][0] - mx) * ex + (obj(b)['position'][1] - my) * ey)
for block, (x, y) in zip(along, spots):
    put(block, x, y, yaw)
