# Goal: "Construct a 2*2*2 cube structure in the zone using 8 blocks of the same color."
# Two 2x2 layers on one grid centred on the zone and turned with it, the pitch 1.125 block sizes
# (a small gap between neighbours); the upper layer goes right on top of the lower one.
words = goal.rstrip('.').split()
nx, ny, nz = [int(k) for k in words[words.index('cube') - 1].split('*')]  # "2*2*2"
zone = [name for name in objects if ' zone ' in name][0]
blocks = [name for name in objects if ' block ' in name]
bbox = get_bbox(blocks[0])
size = bbox[5] - bbox[2]
pitch = 1.125 * size
cx, cy, _ = get_obj_pos(zone)
qx, qy, qz, qw = get_obj_rot(zone)
yaw = math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
quat = [0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)]
for level in range(nz):
    for i in range(ny):
        for j in range(nx):
            u, v = (j - (nx - 1) / 2) * pitch, (i - (ny - 1) / 2) * pitch
            x = cx + math.cos(yaw) * u - math.sin(yaw) * v
            y = cy + math.sin(yaw) * u + math.cos(yaw) * v
            put_first_on_second(blocks.pop(0), ([x, y, (level + 0.5) * size], quat))
