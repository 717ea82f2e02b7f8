# Goal: "Arrange all blocks on the zone bisector line between two symmetrically placed zones evenly
# on the tabletop, and the gap between two adjacent blocks' edges should be near the block size,
# and the line connecting the center of the zones also bisects these blocks."
# The row lies on the perpendicular bisector of the two zone centres, centred on their midpoint,
# neighbours one block size apart edge to edge (centres two block sizes apart), blocks turned
# along the row.  Blocks are taken in their order along the row so no path crosses the row twice.
zones = [name for name in objects if ' zone ' in name]
blocks = [name for name in objects if ' block ' in name]
x1, y1, _ = get_obj_pos(zones[0])
x2, y2, _ = get_obj_pos(zones[1])
mx, my = (x1 + x2) / 2, (y1 + y2) / 2
length = math.hypot(x2 - x1, y2 - y1)
ex, ey = -(y2 - y1) / length, (x2 - x1) / length  # along the bisector
bbox = get_bbox(blocks[0])
pitch = 2 * (bbox[5] - bbox[2])  # the block height is its edge length
yaw = math.atan2(ey, ex)
quat = [0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)]
n = len(blocks)
spots = [[mx + (i - (n - 1) / 2) * pitch * ex, my + (i - (n - 1) / 2) * pitch * ey] for i in range(n)]
along = sorted(blocks, key=lambda b: (get_obj_pos(b)[0] - mx) * ex + (get_obj_pos(b)[1] - my) * ey)
for block, spot in zip(along, spots):
    put_first_on_second(block, (spot, quat))
