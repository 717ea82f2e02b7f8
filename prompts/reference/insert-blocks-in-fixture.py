# Goal: "Each L-shaped fixture can hold three blocks, suppose the block size is (a,a,a), then in
# fixture's local coordinate system, the three places that can hold blocks are
# [(0,0,0),(a,0,0),(0,a,0)]. Fill in all the fixtures ... three blocks with different colors."
# The fixture's reported pose is its local frame.  Sorting the blocks by colour and dealing them
# round robin gives every fixture three different colours (no colour has more blocks than there
# are fixtures).  Slot (0,0,0) of every fixture is filled first, then (a,0,0), then (0,a,0); each
# block goes down exactly at its slot, turned like the fixture.
fixtures = [name for name in objects if ' fixture ' in name]
blocks = sorted([name for name in objects if ' block ' in name], key=lambda b: get_color(b))
bbox = get_bbox(blocks[0])
a = bbox[5] - bbox[2]  # the block height is its edge length
seats = [(0.0, 0.0), (a, 0.0), (0.0, a)]
n = len(fixtures)
for slot in range(3):
    for f, fixture in enumerate(fixtures):
        block = blocks[slot * n + f]
        x, y, _ = get_obj_pos(fixture)
        quat = get_obj_rot(fixture)  # (x, y, z, w)
        yaw = math.atan2(2 * (quat[3] * quat[2] + quat[0] * quat[1]), 1 - 2 * (quat[1] ** 2 + quat[2] ** 2))
        c, s = math.cos(yaw), math.sin(yaw)
        u, v = seats[slot]
        put_first_on_second(block, ([x + c * u - s * v, y + s * u + c * v], quat))
