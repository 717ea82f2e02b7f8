# Goal: "Construct a 9-4-1 rectangular pyramid structure in the zone using 14 blocks of the same color."
# Layers of 3x3, 2x2 and 1 block, built bottom-up on square grids centred on the zone and turned
# with it.  A pitch of 1.25 block sizes leaves gaps between neighbours, and every upper block goes
# onto the middle of the four blocks below it (position and height given, so it lands centred).
words = goal.rstrip('.').split()
layer_counts = [int(k) for k in words[words.index('rectangular') - 1].split('-')]  # "9-4-1"
zone = [name for name in objects if ' zone ' in name][0]
blocks = [name for name in objects if ' block ' in name]
bbox = get_bbox(blocks[0])
size = bbox[5] - bbox[2]
pitch = 1.25 * size
cx, cy, _ = get_obj_pos(zone)
qx, qy, qz, qw = get_obj_rot(zone)
yaw = math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
quat = [0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)]
for level, count in enumerate(layer_counts):
    side = int(round(math.sqrt(count)))
    for i in range(side):
        for j in range(side):
            u, v = (j - (side - 1) / 2) * pitch, (i - (side - 1) / 2) * pitch
            x = cx + math.cos(yaw) * u - math.sin(yaw) * v
            y = cy + math.sin(yaw) * u + math.cos(yaw) * v
            put_first_on_second(blocks.pop(0), ([x, y, (level + 0.5) * size], quat))
