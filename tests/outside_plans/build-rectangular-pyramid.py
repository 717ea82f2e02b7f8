# Goal: "Construct a 9-4-1 rectangular pyramid structure in the zone using 14 blocks of the same color."
# 3 x 3 bottom layer, a 2 x 2 layer over its gaps, one block on top, centred on the zone, grid
# turned like the zone. Layer k's centre height is 0.02 + 0.04 k (small blocks are 4 cm).
zone = [n for n in objects if ' zone ' in n][0]
blocks = [n for n in objects if ' block ' in n]
cx, cy, _ = get_obj_pos(zone)
q = get_obj_rot(zone)
yaw = 2 * math.atan2(q[2], q[3])
c, s = math.cos(yaw), math.sin(yaw)
pitch = 0.042
targets = []
for layer, n in enumerate((3, 2, 1)):
    offsets = [(i - (n - 1) / 2) * pitch for i in range(n)]
    for u in offsets:
        for v in offsets:
            targets.append(([cx + c * u - s * v, cy + s * u + c * v, 0.02 + 0.04 * layer], q))
for block, target in zip(blocks, targets):
    put_first_on_second(block, target)
