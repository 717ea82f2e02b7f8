# Goal: put the largest odd number of blocks of each zone's colour in that zone: side by side on
# six spots of the zone (2 x 3, turned like the zone).
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
SPOTS = [(u, v) for v in (0.0, -0.05, 0.05) for u in (-0.025, 0.025)]
zones = [name for name in objects if ' zone ' in name]
blocks = [name for name in objects if ' block ' in name]
for zone in zones:
    z = obj(zone)
    mine = [block for block in blocks if obj(block)['color'] == z['color']]
    count = len(mine) if len(mine) % 2 == 1 else len(mine) - 1
    x, y, _ = z['position']
    c, s = math.cos(z['yaw']), math.sin(z['yaw'])
    for block, (u, v) in zip(mine[:count], SPOTS):
        put(block, x + c * u - s * v, y + s * u + c * v, z['yaw'])
