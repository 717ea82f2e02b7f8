# Goal: "Construct two concentric circles in the zone using {n} {c1} and {m} {c2} blocks."
# The colour with fewer blocks on the inner circle, the other on the outer one, both around the
# zone centre, blocks evenly spaced and turned to face the centre.  Each radius leaves 1 cm
# between neighbours (two radially turned blocks take size/2 * (cos a + sin a) of the chord each,
# a = pi / count), and the outer circle keeps 1 cm from the inner circle's corners.
words = goal.rstrip('.').split()
at = words.index('using')
groups = [(int(words[at + 1]), words[at + 2]), (int(words[at + 4]), words[at + 5])]
groups.sort()
zone = [name for name in objects if ' zone ' in name][0]
cx, cy, _ = get_obj_pos(zone)
qx, qy, qz, qw = get_obj_rot(zone)
phase = math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))


def ring_radius(count, size):
    a = math.pi / count
    return (size * (math.cos(a) + math.sin(a)) + 0.01) / (2 * math.sin(a))


inner_edge = 0.0
for count, color in groups:
    blocks = [name for name in objects if ' block ' in name and get_color(name) == color]
    bbox = get_bbox(blocks[0])
    size = bbox[5] - bbox[2]
    if inner_edge == 0.0:
        radius = max(1.5 * size, ring_radius(len(blocks), size))
    else:
        radius = max(ring_radius(len(blocks), size), inner_edge + 0.01 + size / 2)
    for k, block in enumerate(blocks):
        angle = phase + 2 * math.pi * k / len(blocks)
        pos = [cx + radius * math.cos(angle), cy + radius * math.sin(angle), size / 2]
        put_first_on_second(block, (pos, [0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2)]))
    inner_edge = math.hypot(radius + size / 2, size / 2)
