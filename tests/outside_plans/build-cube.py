# Goal: "Construct a 2*2*2 cube structure in the zone using 8 blocks of the same color."
# Two layers of a 2 x 2 grid at the zone's centre, world-aligned, 4.2 cm pitch (2 mm gaps so the
# blocks do not scrape each other). A bare [x, y] rests the block on whatever is there, so the
# second layer is the same four points again.
zone = [n for n in objects if ' zone ' in n][0]
blocks = [n for n in objects if ' block ' in n]
cx, cy, _ = get_obj_pos(zone)
pitch = 0.042
cells = [(cx + dx * pitch / 2, cy + dy * pitch / 2) for dx in (-1, 1) for dy in (-1, 1)]
for i, block in enumerate(blocks[:8]):
    x, y = cells[i % 4]
    put_first_on_second(block, [x, y])
