# Goal: "Arrange all blocks on the zone bisector line between two symmetrically placed zones evenly
# on the tabletop, and the gap between two adjacent blocks' edges should be near the block size,
# and the line connecting the center of the zones also bisects these blocks."
# The row runs along the perpendicular bisector of the two zone centres, centred on their midpoint;
# centre spacing = 2 block sizes (gap = one block size); each block turned along the row.
zones = [n for n in objects if ' zone ' in n]
blocks = [n for n in objects if ' block ' in n]
p1, p2 = np.array(get_obj_pos(zones[0])[:2]), np.array(get_obj_pos(zones[1])[:2])
mid = (p1 + p2) / 2
d = (p2 - p1) / np.linalg.norm(p2 - p1)
along = np.array([-d[1], d[0]])
size = 0.04
n = len(blocks)
points = [(mid + along * (i - (n - 1) / 2) * 2 * size).tolist() for i in range(n)]
yaw = math.atan2(along[1], along[0])
quat = [0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)]
for p in points:
    for name in is_target_occupied(p, 0.03):
        if ' block ' in name:
            put_first_on_second(name, get_random_free_pos(targ=points))
for block, p in zip(blocks, points):
    put_first_on_second(block, (p + [0.02], quat))
